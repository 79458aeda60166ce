package plugin

// Covers device IDs (parsing, ordering, checking against the advertised count) and the Slots
// broadcast (a change closes the channel handed out before it; no change, no wake-up).

import "testing"

func TestSlotIndex(t *testing.T) {
	for id, want := range map[string]int{"slot-0": 0, "slot-7": 7, "slot-12": 12} {
		if got, ok := slotIndex(id); !ok || got != want {
			t.Errorf("slotIndex(%q) = %d, %v", id, got, ok)
		}
	}
	for _, id := range []string{"", "slot-", "slot-01", "slot--1", "slot-x", "gpu-0", "slot-1 "} {
		if _, ok := slotIndex(id); ok {
			t.Errorf("slotIndex(%q) accepted", id)
		}
	}
}

func TestCompareSlotsOrdersNumerically(t *testing.T) {
	if compareSlots("slot-2", "slot-10") >= 0 || compareSlots("slot-9", "other") >= 0 ||
		compareSlots("b", "a") <= 0 || compareSlots("slot-3", "slot-3") != 0 {
		t.Error("wrong order")
	}
}

func TestCheckIDs(t *testing.T) {
	if err := checkIDs([]string{"slot-0", "slot-2"}, 3); err != nil {
		t.Error(err)
	}
	if err := checkIDs([]string{"slot-3"}, 3); err == nil {
		t.Error("slot-3 of 3 accepted")
	}
	if err := checkIDs([]string{"slot-0"}, 0); err == nil {
		t.Error("a slot of 0 accepted")
	}
}

func TestSlotsBroadcastChanges(t *testing.T) {
	s := NewSlots(2)
	n, changed := s.Get()
	if n != 2 {
		t.Fatalf("n = %d", n)
	}
	if s.Set(2) {
		t.Error("Set(2) on 2 reported a change")
	}
	select {
	case <-changed:
		t.Fatal("woken without a change")
	default:
	}
	if !s.Set(5) {
		t.Error("Set(5) reported no change")
	}
	select {
	case <-changed:
	default:
		t.Fatal("not woken by a change")
	}
	if n, _ := s.Get(); n != 5 {
		t.Errorf("n = %d", n)
	}
}
