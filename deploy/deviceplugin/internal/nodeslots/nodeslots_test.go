package nodeslots

// Covers Resolve (label, missing label, unusable values) and Source against a fake nodes client:
// the first read applies the label, watch events change the slots (and removing the label falls
// back to the default), a 410 Gone reads the node afresh, a failed read is retried, and Follow
// returns when its context ends.

import (
	"context"
	"errors"
	"io"
	"log/slog"
	"sync"
	"testing"
	"time"

	corev1 "k8s.io/api/core/v1"
	apierrors "k8s.io/apimachinery/pkg/api/errors"
	metav1 "k8s.io/apimachinery/pkg/apis/meta/v1"
	"k8s.io/apimachinery/pkg/runtime/schema"
	"k8s.io/apimachinery/pkg/watch"

	"simtest.dev/deviceplugin/internal/plugin"
)

func TestResolve(t *testing.T) {
	cases := []struct {
		labels  map[string]string
		want    int
		problem bool
	}{
		{nil, 2, false},
		{map[string]string{"other": "9"}, 2, false},
		{map[string]string{DefaultLabel: "5"}, 5, false},
		{map[string]string{DefaultLabel: "0"}, 0, false},
		{map[string]string{DefaultLabel: "256"}, 256, false},
		{map[string]string{DefaultLabel: "257"}, 2, true},
		{map[string]string{DefaultLabel: "-1"}, 2, true},
		{map[string]string{DefaultLabel: "three"}, 2, true},
		{map[string]string{DefaultLabel: ""}, 2, true},
	}
	for _, c := range cases {
		n, problem := Resolve(c.labels, DefaultLabel, 2)
		if n != c.want || (problem != "") != c.problem {
			t.Errorf("Resolve(%v) = %d, %q", c.labels, n, problem)
		}
	}
}

// fakeNodes serves one node; every Watch call hands out a new fake watcher on watchers.
type fakeNodes struct {
	mu       sync.Mutex
	node     *corev1.Node
	getErr   error
	gets     int
	watchers chan *watch.FakeWatcher
	opts     chan metav1.ListOptions
}

func newFakeNodes(labels map[string]string) *fakeNodes {
	return &fakeNodes{
		node:     node("1", labels),
		watchers: make(chan *watch.FakeWatcher, 10),
		opts:     make(chan metav1.ListOptions, 10),
	}
}

func node(rv string, labels map[string]string) *corev1.Node {
	return &corev1.Node{ObjectMeta: metav1.ObjectMeta{Name: "n1", ResourceVersion: rv, Labels: labels}}
}

func (f *fakeNodes) Get(_ context.Context, name string, _ metav1.GetOptions) (*corev1.Node, error) {
	f.mu.Lock()
	defer f.mu.Unlock()
	f.gets++
	if f.getErr != nil {
		err := f.getErr
		f.getErr = nil
		return nil, err
	}
	if name != f.node.Name {
		return nil, apierrors.NewNotFound(schema.GroupResource{Resource: "nodes"}, name)
	}
	return f.node.DeepCopy(), nil
}

func (f *fakeNodes) Watch(_ context.Context, opts metav1.ListOptions) (watch.Interface, error) {
	w := watch.NewFakeWithChanSize(10, false)
	f.opts <- opts
	f.watchers <- w
	return w, nil
}

func (f *fakeNodes) getCount() int {
	f.mu.Lock()
	defer f.mu.Unlock()
	return f.gets
}

func source(f *fakeNodes, slots *plugin.Slots) *Source {
	return &Source{
		Client: f, Node: "n1", Label: DefaultLabel, Default: 1, Slots: slots,
		Log: slog.New(slog.NewTextHandler(io.Discard, nil)), Retry: 10 * time.Millisecond,
	}
}

// waitSlots waits until the slots are want.
func waitSlots(t *testing.T, slots *plugin.Slots, want int) {
	t.Helper()
	deadline := time.After(5 * time.Second)
	for {
		n, changed := slots.Get()
		if n == want {
			return
		}
		select {
		case <-changed:
		case <-deadline:
			t.Fatalf("slots stayed %d, want %d", n, want)
		}
	}
}

func nextWatcher(t *testing.T, f *fakeNodes) (*watch.FakeWatcher, metav1.ListOptions) {
	t.Helper()
	select {
	case w := <-f.watchers:
		return w, <-f.opts
	case <-time.After(5 * time.Second):
		t.Fatal("no watch")
		return nil, metav1.ListOptions{}
	}
}

func TestSourceFollowsTheLabel(t *testing.T) {
	f := newFakeNodes(map[string]string{DefaultLabel: "4"})
	slots := plugin.NewSlots(1)
	s := source(f, slots)
	rv, err := s.Sync(context.Background())
	if err != nil || rv != "1" {
		t.Fatalf("Sync = %q, %v", rv, err)
	}
	if n, _ := slots.Get(); n != 4 {
		t.Fatalf("slots after Sync: %d", n)
	}

	ctx, cancel := context.WithCancel(context.Background())
	done := make(chan struct{})
	go func() { s.Follow(ctx, rv); close(done) }()

	w, opts := nextWatcher(t, f)
	if opts.FieldSelector != "metadata.name=n1" || opts.ResourceVersion != "1" {
		t.Errorf("watch options %+v", opts)
	}
	w.Modify(node("2", map[string]string{DefaultLabel: "2"}))
	waitSlots(t, slots, 2)
	w.Modify(node("3", map[string]string{DefaultLabel: "lots"}))
	waitSlots(t, slots, 1)
	w.Modify(node("4", map[string]string{DefaultLabel: "6"}))
	waitSlots(t, slots, 6)
	w.Modify(node("5", nil))
	waitSlots(t, slots, 1)

	// The server closes the watch: resume after the last version seen, without a read.
	gets := f.getCount()
	w.Stop()
	_, opts = nextWatcher(t, f)
	if opts.ResourceVersion != "5" || f.getCount() != gets {
		t.Errorf("resumed at %q after %d extra reads", opts.ResourceVersion, f.getCount()-gets)
	}

	cancel()
	select {
	case <-done:
	case <-time.After(5 * time.Second):
		t.Fatal("Follow did not return")
	}
}

func TestSourceReadsAgainAfterGoneAndErrors(t *testing.T) {
	f := newFakeNodes(nil)
	slots := plugin.NewSlots(1)
	ctx, cancel := context.WithCancel(context.Background())
	defer cancel()
	go source(f, slots).Follow(ctx, "")

	w, opts := nextWatcher(t, f) // after a first read
	if opts.ResourceVersion != "1" || f.getCount() != 1 {
		t.Fatalf("watch at %q after %d reads", opts.ResourceVersion, f.getCount())
	}
	f.mu.Lock()
	f.node = node("9", map[string]string{DefaultLabel: "3"})
	f.getErr = errors.New("connection refused") // the next read fails once, then works
	f.mu.Unlock()
	w.Error(&apierrors.NewResourceExpired("too old").ErrStatus)

	_, opts = nextWatcher(t, f)
	if opts.ResourceVersion != "9" || f.getCount() != 3 {
		t.Errorf("watch at %q after %d reads", opts.ResourceVersion, f.getCount())
	}
	waitSlots(t, slots, 3)
}
