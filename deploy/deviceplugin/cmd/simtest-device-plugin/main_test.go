package main

// Covers the command line: defaults (NODE_NAME from the environment), refused values with exit
// code 2, --version, and that the label override stays off without a node name.

import (
	"bytes"
	"io"
	"log/slog"
	"strings"
	"testing"
	"time"

	"simtest.dev/deviceplugin/internal/plugin"
)

func TestDefaults(t *testing.T) {
	t.Setenv("NODE_NAME", "node-7")
	o, err := parse(nil, io.Discard)
	if err != nil {
		t.Fatal(err)
	}
	want := options{
		slots: 1, dir: "/var/lib/kubelet/device-plugins/", socket: "simtest-simulator.sock",
		resource: "simtest.dev/simulator", nodeName: "node-7", label: "simtest.dev/simulator-slots",
		watchInterval: time.Second, logLevel: "info",
	}
	if o != want {
		t.Errorf("defaults\n got %+v\nwant %+v", o, want)
	}
}

func TestRefusedArguments(t *testing.T) {
	for _, args := range [][]string{
		{"--slots", "-1"}, {"--slots", "1000"}, {"--watch-interval", "0s"}, {"extra"},
		{"--log-level", "loud"}, {"--no-such-flag"},
	} {
		var stderr bytes.Buffer
		if code := run(args, io.Discard, &stderr); code != 2 || stderr.Len() == 0 {
			t.Errorf("%v: exit %d, stderr %q", args, code, stderr.String())
		}
	}
}

func TestVersion(t *testing.T) {
	var stdout bytes.Buffer
	if code := run([]string{"--version"}, &stdout, io.Discard); code != 0 ||
		!strings.HasPrefix(stdout.String(), "simtest-device-plugin ") {
		t.Errorf("exit %d, %q", code, stdout.String())
	}
}

func TestLabelOverrideNeedsANodeName(t *testing.T) {
	t.Setenv("NODE_NAME", "")
	o, _ := parse([]string{"--kubeconfig", "/nonexistent"}, io.Discard)
	log := slog.New(slog.NewTextHandler(io.Discard, nil))
	if labelSource(o, plugin.NewSlots(1), log) != nil {
		t.Error("override on without a node name")
	}
	o, _ = parse([]string{"--node-name", "n", "--kubeconfig", "/nonexistent"}, io.Discard)
	if labelSource(o, plugin.NewSlots(1), log) != nil {
		t.Error("override on without usable credentials")
	}
}
