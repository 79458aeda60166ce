package plugin

import (
	"fmt"
	"strconv"
	"strings"
	"sync"

	pluginapi "k8s.io/kubelet/pkg/apis/deviceplugin/v1beta1"
)

// slotPrefix names the devices: slot-0 .. slot-<n-1>. The names are stable across restarts, so
// the kubelet's checkpoint (which pod holds which device) stays valid when the plugin comes back.
const slotPrefix = "slot-"

// Slots is the number of simulator slots the node advertises. It is shared by the gRPC service
// (ListAndWatch streams every change to the kubelet) and whatever decides the number (the --slots
// flag, then the node label). The zero value is not usable; call NewSlots.
type Slots struct {
	mu      sync.Mutex
	n       int
	changed chan struct{} // closed and replaced on every change
}

// NewSlots starts with n slots.
func NewSlots(n int) *Slots {
	return &Slots{n: n, changed: make(chan struct{})}
}

// Set changes the number of slots and wakes every ListAndWatch stream; it reports whether the
// number changed.
func (s *Slots) Set(n int) bool {
	s.mu.Lock()
	defer s.mu.Unlock()
	if n == s.n {
		return false
	}
	s.n = n
	close(s.changed)
	s.changed = make(chan struct{})
	return true
}

// Get returns the number of slots and a channel that is closed at the next change.
func (s *Slots) Get() (int, <-chan struct{}) {
	s.mu.Lock()
	defer s.mu.Unlock()
	return s.n, s.changed
}

// SlotID is the device ID of slot i.
func SlotID(i int) string { return slotPrefix + strconv.Itoa(i) }

// slotIndex parses a device ID; ok is false for anything that is not slot-<i>.
func slotIndex(id string) (int, bool) {
	digits, found := strings.CutPrefix(id, slotPrefix)
	if !found || digits == "" || (len(digits) > 1 && digits[0] == '0') {
		return 0, false
	}
	i, err := strconv.Atoi(digits)
	return i, err == nil && i >= 0
}

// devices is what ListAndWatch sends for n slots: all healthy (a slot is a unit of admission,
// not hardware, so it cannot fail).
func devices(n int) []*pluginapi.Device {
	list := make([]*pluginapi.Device, n)
	for i := range list {
		list[i] = &pluginapi.Device{ID: SlotID(i), Health: pluginapi.Healthy}
	}
	return list
}

// checkIDs refuses device IDs that are not among the n slots advertised now.
func checkIDs(ids []string, n int) error {
	for _, id := range ids {
		if i, ok := slotIndex(id); !ok || i >= n {
			return fmt.Errorf("unknown device %q (this node advertises %d slots: %s..%s)",
				id, n, SlotID(0), SlotID(max(n-1, 0)))
		}
	}
	return nil
}
