// Package plugin is a kubelet device plugin (API v1beta1) whose devices are simulator slots: one
// unit of the extended resource simtest.dev/simulator admits one simulator pod to the node.
//
// Lifecycle (what the kubelet expects of a device plugin): serve the DevicePlugin service on a
// unix socket in the kubelet's device-plugin directory, call Register on the kubelet's
// kubelet.sock in the same directory, and stream the devices from ListAndWatch. A starting
// kubelet deletes every socket in that directory and opens a new kubelet.sock, so the plugin
// checks both files every WatchInterval; when its own socket is gone or kubelet.sock is a new
// file, it serves a fresh socket and registers again. Running pods keep their slots throughout:
// the kubelet's checkpoint maps them to the stable device IDs.
package plugin

import (
	"context"
	"errors"
	"fmt"
	"log/slog"
	"net"
	"os"
	"path/filepath"
	"time"

	"google.golang.org/grpc"
	"google.golang.org/grpc/credentials/insecure"
	pluginapi "k8s.io/kubelet/pkg/apis/deviceplugin/v1beta1"
)

// KubeletSocket is the kubelet's registration socket inside the device-plugin directory.
const KubeletSocket = "kubelet.sock"

// Config says where to serve and what to register.
type Config struct {
	// Dir is the kubelet's device-plugin directory (pluginapi.DevicePluginPath by default; the
	// kubelet uses that path whatever its --root-dir).
	Dir string
	// Socket is the file name of the plugin's socket in Dir (the Endpoint sent to the kubelet).
	Socket string
	// ResourceName is the extended resource, simtest.dev/simulator.
	ResourceName string
	// WatchInterval is how often the two sockets are checked for a kubelet restart.
	WatchInterval time.Duration
	// RegisterTimeout bounds one Register call (the kubelet dials back before it answers).
	RegisterTimeout time.Duration
}

// Plugin serves the slots of one node until its context ends.
type Plugin struct {
	cfg   Config
	slots *Slots
	log   *slog.Logger
}

// New returns a plugin advertising slots.
func New(cfg Config, slots *Slots, log *slog.Logger) *Plugin {
	return &Plugin{cfg: cfg, slots: slots, log: log}
}

// SocketPath is the plugin's own socket.
func (p *Plugin) SocketPath() string { return filepath.Join(p.cfg.Dir, p.cfg.Socket) }

func (p *Plugin) kubeletPath() string { return filepath.Join(p.cfg.Dir, KubeletSocket) }

// Run serves, registers and re-registers after every kubelet restart. It returns nil when ctx
// ends (SIGTERM), after stopping the server and removing its socket, and an error only when the
// socket cannot be created at all.
func (p *Plugin) Run(ctx context.Context) error {
	for {
		srv, err := p.serve()
		if err != nil {
			return err
		}
		reason := p.registerAndWatch(ctx, srv)
		srv.stop()
		if ctx.Err() != nil {
			p.log.Info("stopped", "socket", srv.path)
			return nil
		}
		p.log.Info("restarting", "reason", reason)
	}
}

// server is one gRPC server on one socket file.
type server struct {
	path   string
	file   os.FileInfo // the socket as created, to notice its removal or replacement
	grpc   *grpc.Server
	failed chan error // Serve's error, if it ends on its own
}

func (p *Plugin) serve() (*server, error) {
	path := p.SocketPath()
	if err := os.MkdirAll(p.cfg.Dir, 0o750); err != nil {
		return nil, fmt.Errorf("device-plugin directory: %w", err)
	}
	if err := os.Remove(path); err != nil && !errors.Is(err, os.ErrNotExist) {
		return nil, fmt.Errorf("remove stale socket: %w", err)
	}
	ln, err := net.Listen("unix", path)
	if err != nil {
		return nil, fmt.Errorf("listen on %s: %w", path, err)
	}
	// Keep the file when the listener closes: stop() removes it only if it is still ours.
	ln.(*net.UnixListener).SetUnlinkOnClose(false)
	info, err := os.Stat(path)
	if err != nil {
		ln.Close()
		return nil, fmt.Errorf("stat %s: %w", path, err)
	}
	srv := &server{path: path, file: info, grpc: grpc.NewServer(), failed: make(chan error, 1)}
	pluginapi.RegisterDevicePluginServer(srv.grpc, &service{slots: p.slots, log: p.log})
	go func() { srv.failed <- srv.grpc.Serve(ln) }()
	p.log.Info("serving", "socket", path)
	return srv, nil
}

// stop ends every stream (the kubelet sees the plugin go away) and removes the socket unless
// someone else (a new kubelet, a new plugin instance) has replaced it meanwhile.
func (s *server) stop() {
	s.grpc.Stop()
	if info, err := os.Stat(s.path); err == nil && sameFile(info, s.file) {
		_ = os.Remove(s.path)
	}
}

// registerAndWatch registers (retrying until the kubelet answers) and then waits for a reason to
// start over; it returns that reason, or "" when ctx ended.
func (p *Plugin) registerAndWatch(ctx context.Context, srv *server) string {
	tick := time.NewTicker(p.cfg.WatchInterval)
	defer tick.Stop()
	var kubelet os.FileInfo // kubelet.sock as it was when Register succeeded
	backoff, nextTry := p.cfg.WatchInterval, time.Now()
	failures, waitLogged := 0, false
	for {
		if reason := srv.check(); reason != "" {
			return reason
		}
		current, _ := os.Stat(p.kubeletPath())
		switch {
		case kubelet != nil && current != nil && !sameFile(current, kubelet):
			return "kubelet.sock was recreated (kubelet restarted)"
		case kubelet == nil && current != nil && !time.Now().Before(nextTry):
			if err := p.register(ctx); err != nil {
				failures++
				if failures == 1 || failures%30 == 0 {
					p.log.Warn("register failed; retrying", "attempt", failures, "err", err)
				}
				backoff = min(backoff*2, 10*time.Second)
				nextTry = time.Now().Add(backoff)
				break
			}
			kubelet = current
			p.log.Info("registered", "resource", p.cfg.ResourceName, "kubelet", p.kubeletPath())
		case kubelet == nil && current == nil && !waitLogged:
			waitLogged = true
			p.log.Info("waiting for the kubelet", "socket", p.kubeletPath())
		}
		select {
		case <-ctx.Done():
			return ""
		case err := <-srv.failed:
			return fmt.Sprintf("gRPC server ended: %v", err)
		case <-tick.C:
		}
	}
}

// check reports why this socket is no longer the plugin's endpoint ("" while it is).
func (s *server) check() string {
	info, err := os.Stat(s.path)
	switch {
	case err != nil:
		return s.path + " was removed (kubelet restarted)"
	case !sameFile(info, s.file):
		return s.path + " was replaced"
	}
	return ""
}

// register calls the kubelet's Registration service once.
func (p *Plugin) register(ctx context.Context) error {
	conn, err := grpc.NewClient("unix://"+p.kubeletPath(), grpc.WithTransportCredentials(insecure.NewCredentials()))
	if err != nil {
		return err
	}
	defer conn.Close()
	ctx, cancel := context.WithTimeout(ctx, p.cfg.RegisterTimeout)
	defer cancel()
	_, err = pluginapi.NewRegistrationClient(conn).Register(ctx, &pluginapi.RegisterRequest{
		Version:      pluginapi.Version,
		Endpoint:     p.cfg.Socket,
		ResourceName: p.cfg.ResourceName,
		Options:      &pluginapi.DevicePluginOptions{},
	})
	return err
}

// sameFile is os.SameFile plus the modification time, since a recreated socket may get the
// inode number of the one it replaced.
func sameFile(a, b os.FileInfo) bool {
	return os.SameFile(a, b) && a.ModTime().Equal(b.ModTime())
}
