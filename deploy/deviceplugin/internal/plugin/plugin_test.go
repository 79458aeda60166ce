package plugin

// Covers the plugin against a fake kubelet on a temp socket: registration (version, resource
// name, endpoint), ListAndWatch (N healthy slots, then every change), Allocate (env per container,
// unknown devices refused), the trivial calls, waiting for a kubelet that is not up yet, retrying
// a refused registration, re-registering after a kubelet restart (sockets wiped and kubelet.sock
// recreated, or kubelet.sock recreated alone), and a clean stop that removes the socket.

import (
	"context"
	"errors"
	"io"
	"log/slog"
	"net"
	"os"
	"path/filepath"
	"sync/atomic"
	"testing"
	"time"

	"google.golang.org/grpc"
	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/credentials/insecure"
	"google.golang.org/grpc/status"
	pluginapi "k8s.io/kubelet/pkg/apis/deviceplugin/v1beta1"
)

const (
	testResource = "simtest.dev/simulator"
	testSocket   = "simtest-test.sock"
	waitFor      = 5 * time.Second
)

// fakeKubelet serves the Registration service on <dir>/kubelet.sock and, like the real kubelet,
// dials the plugin's endpoint before it accepts a registration.
type fakeKubelet struct {
	pluginapi.UnimplementedRegistrationServer

	t        *testing.T
	dir      string
	srv      *grpc.Server
	requests chan *pluginapi.RegisterRequest
	refuse   atomic.Int32 // refuse this many registrations first
}

func startKubelet(t *testing.T, dir string) *fakeKubelet {
	t.Helper()
	k := &fakeKubelet{t: t, dir: dir, requests: make(chan *pluginapi.RegisterRequest, 10)}
	k.start()
	t.Cleanup(func() { k.srv.Stop() })
	return k
}

func (k *fakeKubelet) start() {
	k.t.Helper()
	ln, err := net.Listen("unix", filepath.Join(k.dir, KubeletSocket))
	if err != nil {
		k.t.Fatal(err)
	}
	k.srv = grpc.NewServer()
	pluginapi.RegisterRegistrationServer(k.srv, k)
	go func() { _ = k.srv.Serve(ln) }()
}

// restart does what a starting kubelet does: stop, delete every socket in the directory (wipe)
// or only its own, and listen on a new kubelet.sock.
func (k *fakeKubelet) restart(wipe bool) {
	k.t.Helper()
	k.srv.Stop()
	entries, err := os.ReadDir(k.dir)
	if err != nil {
		k.t.Fatal(err)
	}
	for _, e := range entries {
		if wipe || e.Name() == KubeletSocket {
			_ = os.Remove(filepath.Join(k.dir, e.Name()))
		}
	}
	time.Sleep(10 * time.Millisecond) // a new file gets a new modification time
	k.start()
}

func (k *fakeKubelet) Register(ctx context.Context, req *pluginapi.RegisterRequest) (*pluginapi.Empty, error) {
	if k.refuse.Add(-1) >= 0 {
		return nil, status.Error(codes.Unavailable, "not ready")
	}
	conn, err := grpc.NewClient("unix://"+filepath.Join(k.dir, req.Endpoint),
		grpc.WithTransportCredentials(insecure.NewCredentials()))
	if err != nil {
		return nil, err
	}
	defer conn.Close()
	if _, err := pluginapi.NewDevicePluginClient(conn).GetDevicePluginOptions(ctx, &pluginapi.Empty{}); err != nil {
		return nil, err
	}
	k.requests <- req
	return &pluginapi.Empty{}, nil
}

func (k *fakeKubelet) nextRequest() *pluginapi.RegisterRequest {
	k.t.Helper()
	select {
	case req := <-k.requests:
		return req
	case <-time.After(waitFor):
		k.t.Fatal("no registration within", waitFor)
		return nil
	}
}

func dial(t *testing.T, path string) pluginapi.DevicePluginClient {
	t.Helper()
	conn, err := grpc.NewClient("unix://"+path, grpc.WithTransportCredentials(insecure.NewCredentials()))
	if err != nil {
		t.Fatal(err)
	}
	t.Cleanup(func() { conn.Close() })
	return pluginapi.NewDevicePluginClient(conn)
}

// shortDir is a temp directory short enough for a unix socket path (108 bytes).
func shortDir(t *testing.T) string {
	t.Helper()
	dir, err := os.MkdirTemp("", "dp")
	if err != nil {
		t.Fatal(err)
	}
	t.Cleanup(func() { os.RemoveAll(dir) })
	return dir
}

type running struct {
	plugin *Plugin
	slots  *Slots
	cancel context.CancelFunc
	done   chan error
}

func startPlugin(t *testing.T, dir string, n int) *running {
	t.Helper()
	slots := NewSlots(n)
	p := New(Config{
		Dir:             dir,
		Socket:          testSocket,
		ResourceName:    testResource,
		WatchInterval:   20 * time.Millisecond,
		RegisterTimeout: time.Second,
	}, slots, slog.New(slog.NewTextHandler(io.Discard, nil)))
	ctx, cancel := context.WithCancel(context.Background())
	r := &running{plugin: p, slots: slots, cancel: cancel, done: make(chan error, 1)}
	go func() { r.done <- p.Run(ctx) }()
	t.Cleanup(func() { r.stop(t) })
	return r
}

func (r *running) stop(t *testing.T) error {
	t.Helper()
	r.cancel()
	select {
	case err, ok := <-r.done:
		if ok {
			close(r.done)
		}
		return err
	case <-time.After(waitFor):
		t.Fatal("Run did not return after cancel")
		return nil
	}
}

func deviceIDs(t *testing.T, stream grpc.ServerStreamingClient[pluginapi.ListAndWatchResponse]) []string {
	t.Helper()
	resp, err := stream.Recv()
	if err != nil {
		t.Fatal(err)
	}
	ids := []string{}
	for _, d := range resp.Devices {
		if d.Health != pluginapi.Healthy {
			t.Errorf("device %s is %s", d.ID, d.Health)
		}
		ids = append(ids, d.ID)
	}
	return ids
}

func equal(a, b []string) bool {
	if len(a) != len(b) {
		return false
	}
	for i := range a {
		if a[i] != b[i] {
			return false
		}
	}
	return true
}

func TestRegistersAndAdvertisesSlots(t *testing.T) {
	dir := shortDir(t)
	kubelet := startKubelet(t, dir)
	r := startPlugin(t, dir, 3)

	req := kubelet.nextRequest()
	if req.Version != "v1beta1" || req.ResourceName != testResource || req.Endpoint != testSocket {
		t.Fatalf("register request %v", req)
	}
	ctx, cancel := context.WithTimeout(context.Background(), waitFor)
	defer cancel()
	client := dial(t, r.plugin.SocketPath())
	stream, err := client.ListAndWatch(ctx, &pluginapi.Empty{})
	if err != nil {
		t.Fatal(err)
	}
	if ids := deviceIDs(t, stream); !equal(ids, []string{"slot-0", "slot-1", "slot-2"}) {
		t.Fatalf("devices %v", ids)
	}
	r.slots.Set(1)
	if ids := deviceIDs(t, stream); !equal(ids, []string{"slot-0"}) {
		t.Fatalf("devices after Set(1): %v", ids)
	}
	r.slots.Set(0)
	if ids := deviceIDs(t, stream); len(ids) != 0 {
		t.Fatalf("devices after Set(0): %v", ids)
	}
}

func TestServiceCalls(t *testing.T) {
	dir := shortDir(t)
	kubelet := startKubelet(t, dir)
	r := startPlugin(t, dir, 4)
	kubelet.nextRequest() // the plugin registers only once it serves its socket
	ctx, cancel := context.WithTimeout(context.Background(), waitFor)
	defer cancel()
	client := dial(t, r.plugin.SocketPath())

	opts, err := client.GetDevicePluginOptions(ctx, &pluginapi.Empty{})
	if err != nil || opts.PreStartRequired || opts.GetPreferredAllocationAvailable {
		t.Fatalf("options %v, %v", opts, err)
	}
	alloc, err := client.Allocate(ctx, &pluginapi.AllocateRequest{ContainerRequests: []*pluginapi.ContainerAllocateRequest{
		{DevicesIds: []string{"slot-1"}},
		{DevicesIds: []string{"slot-3", "slot-0"}},
	}})
	if err != nil {
		t.Fatal(err)
	}
	if len(alloc.ContainerResponses) != 2 {
		t.Fatalf("responses %v", alloc.ContainerResponses)
	}
	for i, want := range []string{"slot-1", "slot-3,slot-0"} {
		if got := alloc.ContainerResponses[i].Envs[EnvSlots]; got != want {
			t.Errorf("container %d: %s=%q, want %q", i, EnvSlots, got, want)
		}
	}
	for _, bad := range []string{"slot-4", "slot-01", "gpu-0", "slot-"} {
		_, err = client.Allocate(ctx, &pluginapi.AllocateRequest{ContainerRequests: []*pluginapi.ContainerAllocateRequest{
			{DevicesIds: []string{bad}},
		}})
		if status.Code(err) != codes.InvalidArgument {
			t.Errorf("Allocate(%s): %v, want InvalidArgument", bad, err)
		}
	}
	pref, err := client.GetPreferredAllocation(ctx, &pluginapi.PreferredAllocationRequest{
		ContainerRequests: []*pluginapi.ContainerPreferredAllocationRequest{{
			AvailableDeviceIDs:   []string{"slot-10", "slot-3", "slot-2", "slot-9"},
			MustIncludeDeviceIDs: []string{"slot-9"},
			AllocationSize:       3,
		}},
	})
	if err != nil {
		t.Fatal(err)
	}
	if got := pref.ContainerResponses[0].DeviceIDs; !equal(got, []string{"slot-9", "slot-2", "slot-3"}) {
		t.Errorf("preferred %v", got)
	}
	if _, err := client.PreStartContainer(ctx, &pluginapi.PreStartContainerRequest{DevicesIds: []string{"slot-0"}}); err != nil {
		t.Errorf("PreStartContainer: %v", err)
	}
}

func TestWaitsForTheKubelet(t *testing.T) {
	dir := shortDir(t)
	startPlugin(t, dir, 1)
	time.Sleep(100 * time.Millisecond)
	kubelet := startKubelet(t, dir)
	if req := kubelet.nextRequest(); req.ResourceName != testResource {
		t.Fatalf("register request %v", req)
	}
}

func TestRetriesARefusedRegistration(t *testing.T) {
	dir := shortDir(t)
	kubelet := startKubelet(t, dir)
	kubelet.refuse.Store(2)
	startPlugin(t, dir, 1)
	kubelet.nextRequest()
	if left := kubelet.refuse.Load(); left >= 0 {
		t.Fatalf("registered with %d refusals left", left+1)
	}
}

func TestReRegistersAfterAKubeletRestart(t *testing.T) {
	for name, wipe := range map[string]bool{"sockets wiped": true, "kubelet.sock only": false} {
		t.Run(name, func(t *testing.T) {
			dir := shortDir(t)
			kubelet := startKubelet(t, dir)
			r := startPlugin(t, dir, 2)
			kubelet.nextRequest()

			kubelet.restart(wipe)
			if req := kubelet.nextRequest(); req.Endpoint != testSocket {
				t.Fatalf("re-register request %v", req)
			}
			// The new socket serves the same slots.
			ctx, cancel := context.WithTimeout(context.Background(), waitFor)
			defer cancel()
			stream, err := dial(t, r.plugin.SocketPath()).ListAndWatch(ctx, &pluginapi.Empty{})
			if err != nil {
				t.Fatal(err)
			}
			if ids := deviceIDs(t, stream); !equal(ids, []string{"slot-0", "slot-1"}) {
				t.Fatalf("devices %v", ids)
			}
			select {
			case req := <-kubelet.requests:
				t.Fatalf("registered once too often: %v", req)
			case <-time.After(100 * time.Millisecond):
			}
		})
	}
}

func TestStopEndsStreamsAndRemovesTheSocket(t *testing.T) {
	dir := shortDir(t)
	kubelet := startKubelet(t, dir)
	r := startPlugin(t, dir, 1)
	kubelet.nextRequest()
	ctx, cancel := context.WithTimeout(context.Background(), waitFor)
	defer cancel()
	stream, err := dial(t, r.plugin.SocketPath()).ListAndWatch(ctx, &pluginapi.Empty{})
	if err != nil {
		t.Fatal(err)
	}
	deviceIDs(t, stream)

	if err := r.stop(t); err != nil {
		t.Fatalf("Run returned %v", err)
	}
	if _, err := stream.Recv(); err == nil {
		t.Error("the stream is still open")
	}
	if _, err := os.Stat(r.plugin.SocketPath()); !errors.Is(err, os.ErrNotExist) {
		t.Errorf("socket left behind: %v", err)
	}
	if _, err := os.Stat(filepath.Join(dir, KubeletSocket)); err != nil {
		t.Errorf("the kubelet's socket was touched: %v", err)
	}
}

func TestRunFailsWithoutADirectory(t *testing.T) {
	file := filepath.Join(shortDir(t), "file")
	if err := os.WriteFile(file, nil, 0o600); err != nil {
		t.Fatal(err)
	}
	p := New(Config{Dir: file, Socket: testSocket, WatchInterval: time.Millisecond}, NewSlots(1),
		slog.New(slog.NewTextHandler(io.Discard, nil)))
	if err := p.Run(context.Background()); err == nil {
		t.Fatal("Run succeeded with a file as its directory")
	}
}
