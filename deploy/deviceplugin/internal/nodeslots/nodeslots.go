// Package nodeslots lets a Node label override the slot count of the node it is on, so one
// DaemonSet serves nodes of different sizes: `kubectl label node big simtest.dev/simulator-slots=4`.
//
// It reads the node once at startup (so the first advertisement is already right) and then
// watches that one node (field selector metadata.name); a label change reaches the kubelet within
// seconds through ListAndWatch, with no restart. Removing the label, or a value that is not a
// whole number in [0, MaxSlots], falls back to the --slots default (the latter with a warning).
// It needs get and watch on nodes, nothing else.
package nodeslots

import (
	"context"
	"fmt"
	"log/slog"
	"strconv"
	"time"

	corev1 "k8s.io/api/core/v1"
	apierrors "k8s.io/apimachinery/pkg/api/errors"
	metav1 "k8s.io/apimachinery/pkg/apis/meta/v1"
	"k8s.io/apimachinery/pkg/fields"
	"k8s.io/apimachinery/pkg/watch"

	"simtest.dev/deviceplugin/internal/plugin"
)

// DefaultLabel is the node label that overrides --slots.
const DefaultLabel = "simtest.dev/simulator-slots"

// MaxSlots bounds a label value: a typo such as 300 instead of 3 should not let hundreds of
// simulators onto one node.
const MaxSlots = 256

// NodeClient is the part of the typed core/v1 nodes client this package uses (a fake in tests).
type NodeClient interface {
	Get(ctx context.Context, name string, opts metav1.GetOptions) (*corev1.Node, error)
	Watch(ctx context.Context, opts metav1.ListOptions) (watch.Interface, error)
}

// Resolve is the slot count for a node's labels: the label's value, or def when it is missing;
// problem explains an unusable value (def is used then).
func Resolve(labels map[string]string, label string, def int) (n int, problem string) {
	value, ok := labels[label]
	if !ok {
		return def, ""
	}
	n, err := strconv.Atoi(value)
	if err != nil || n < 0 || n > MaxSlots {
		return def, fmt.Sprintf("label %s=%q is not a whole number in [0, %d]; using %d", label, value, MaxSlots, def)
	}
	return n, ""
}

// Source keeps Slots in step with one node's label.
type Source struct {
	Client  NodeClient
	Node    string
	Label   string
	Default int
	Slots   *plugin.Slots
	Log     *slog.Logger
	// Retry is the pause after a failed read or watch.
	Retry time.Duration

	lastProblem string
}

// Sync reads the node once and applies its label; it returns the node's resourceVersion.
func (s *Source) Sync(ctx context.Context) (string, error) {
	node, err := s.Client.Get(ctx, s.Node, metav1.GetOptions{})
	if err != nil {
		return "", fmt.Errorf("get node %s: %w", s.Node, err)
	}
	s.apply(node)
	return node.ResourceVersion, nil
}

// Follow watches the node until ctx ends, starting after resourceVersion (empty: read it first).
func (s *Source) Follow(ctx context.Context, resourceVersion string) {
	failures := 0
	for ctx.Err() == nil {
		var err error
		if resourceVersion == "" {
			resourceVersion, err = s.Sync(ctx)
		}
		if err == nil {
			resourceVersion, err = s.watch(ctx, resourceVersion)
		}
		if err == nil || ctx.Err() != nil {
			failures = 0
			continue
		}
		failures++
		if failures == 1 || failures%20 == 0 {
			s.Log.Warn("following the node label failed; retrying", "node", s.Node, "attempt", failures, "err", err)
		}
		select {
		case <-ctx.Done():
		case <-time.After(s.Retry):
		}
	}
}

// watch applies events until the watch ends; it returns where to resume ("" after an error
// event, e.g. 410 Gone, so that the node is read afresh).
func (s *Source) watch(ctx context.Context, resourceVersion string) (string, error) {
	w, err := s.Client.Watch(ctx, metav1.ListOptions{
		FieldSelector:       fields.OneTermEqualSelector("metadata.name", s.Node).String(),
		ResourceVersion:     resourceVersion,
		AllowWatchBookmarks: true,
	})
	if err != nil {
		return "", fmt.Errorf("watch node %s: %w", s.Node, err)
	}
	defer w.Stop()
	for {
		select {
		case <-ctx.Done():
			return resourceVersion, nil
		case event, open := <-w.ResultChan():
			if !open {
				return resourceVersion, nil // the server's timeout: resume where we were
			}
			switch event.Type {
			case watch.Added, watch.Modified:
				if node, ok := event.Object.(*corev1.Node); ok {
					s.apply(node)
					resourceVersion = node.ResourceVersion
				}
			case watch.Bookmark:
				if node, ok := event.Object.(*corev1.Node); ok {
					resourceVersion = node.ResourceVersion
				}
			case watch.Error:
				err := apierrors.FromObject(event.Object)
				if apierrors.IsResourceExpired(err) || apierrors.IsGone(err) {
					return "", nil
				}
				return "", fmt.Errorf("watch node %s: %w", s.Node, err)
			case watch.Deleted:
				// The node object is gone (the kubelet will create it again); keep the slots.
			}
		}
	}
}

func (s *Source) apply(node *corev1.Node) {
	n, problem := Resolve(node.Labels, s.Label, s.Default)
	if problem != "" && problem != s.lastProblem {
		s.Log.Warn("ignoring node label", "node", s.Node, "problem", problem)
	}
	s.lastProblem = problem
	if s.Slots.Set(n) {
		source := "label " + s.Label
		if _, ok := node.Labels[s.Label]; !ok || problem != "" {
			source = "--slots"
		}
		s.Log.Info("slots changed", "slots", n, "from", source, "node", s.Node)
	}
}
