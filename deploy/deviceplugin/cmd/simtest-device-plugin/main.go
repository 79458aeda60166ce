// Command simtest-device-plugin makes a node advertise the extended resource
// simtest.dev/simulator to the kubelet: one unit admits one simulator pod, so the scheduler
// places at most <slots> simulators on the node. Run it on every simulator node (the operator
// chart's DaemonSet, devicePlugin.enabled=true), or by hand next to a kubelet:
//
//	simtest-device-plugin --slots 3
//	NODE_NAME=node-1 simtest-device-plugin --kubeconfig node.kubeconfig   # label override
package main

import (
	"context"
	"errors"
	"flag"
	"fmt"
	"io"
	"log/slog"
	"os"
	"os/signal"
	"syscall"
	"time"

	corev1client "k8s.io/client-go/kubernetes/typed/core/v1"
	"k8s.io/client-go/rest"
	"k8s.io/client-go/tools/clientcmd"
	"k8s.io/klog/v2"
	pluginapi "k8s.io/kubelet/pkg/apis/deviceplugin/v1beta1"

	"simtest.dev/deviceplugin/internal/nodeslots"
	"simtest.dev/deviceplugin/internal/plugin"
)

// version is stamped by deploy/devcluster/build.sh (-X main.version=<content hash>).
var version = "dev"

// options are the command line; every flag has a default that works next to a stock kubelet.
type options struct {
	slots         int
	dir           string
	socket        string
	resource      string
	nodeName      string
	label         string
	kubeconfig    string
	watchInterval time.Duration
	logLevel      string
	showVersion   bool
}

func parse(args []string, stderr io.Writer) (options, error) {
	var o options
	fs := flag.NewFlagSet("simtest-device-plugin", flag.ContinueOnError)
	fs.SetOutput(stderr)
	fs.IntVar(&o.slots, "slots", 1, "simulator slots this node advertises (overridden by the node label)")
	fs.StringVar(&o.dir, "device-plugin-path", pluginapi.DevicePluginPath,
		"the kubelet's device-plugin directory (holds kubelet.sock; the kubelet uses the default whatever its --root-dir)")
	fs.StringVar(&o.socket, "socket-name", "simtest-simulator.sock", "file name of this plugin's socket in --device-plugin-path")
	fs.StringVar(&o.resource, "resource-name", "simtest.dev/simulator", "extended resource to advertise")
	fs.StringVar(&o.nodeName, "node-name", os.Getenv("NODE_NAME"), "this node's name, for the label override (default $NODE_NAME)")
	fs.StringVar(&o.label, "slots-label", nodeslots.DefaultLabel, "node label that overrides --slots; empty: no override, no API access")
	fs.StringVar(&o.kubeconfig, "kubeconfig", "", "kubeconfig for reading the node (default: in-cluster credentials)")
	fs.DurationVar(&o.watchInterval, "watch-interval", time.Second, "how often to check for a kubelet restart")
	fs.StringVar(&o.logLevel, "log-level", "info", "debug, info, warn or error")
	fs.BoolVar(&o.showVersion, "version", false, "print the version and exit")
	if err := fs.Parse(args); err != nil {
		return o, err
	}
	switch {
	case fs.NArg() > 0:
		return o, fmt.Errorf("unexpected arguments: %v", fs.Args())
	case o.slots < 0 || o.slots > nodeslots.MaxSlots:
		return o, fmt.Errorf("--slots must be in [0, %d], not %d", nodeslots.MaxSlots, o.slots)
	case o.watchInterval <= 0:
		return o, errors.New("--watch-interval must be positive")
	}
	return o, nil
}

func main() { os.Exit(run(os.Args[1:], os.Stdout, os.Stderr)) }

func run(args []string, stdout, stderr io.Writer) int {
	o, err := parse(args, stderr)
	if errors.Is(err, flag.ErrHelp) {
		return 0
	} else if err != nil {
		fmt.Fprintln(stderr, "simtest-device-plugin:", err)
		return 2
	}
	if o.showVersion {
		fmt.Fprintln(stdout, "simtest-device-plugin", version)
		return 0
	}
	var level slog.Level
	if err := level.UnmarshalText([]byte(o.logLevel)); err != nil {
		fmt.Fprintln(stderr, "simtest-device-plugin: --log-level:", err)
		return 2
	}
	log := slog.New(slog.NewTextHandler(stderr, &slog.HandlerOptions{Level: level}))
	klog.SetSlogLogger(log) // client-go's own messages in the same format

	ctx, stop := signal.NotifyContext(context.Background(), syscall.SIGTERM, syscall.SIGINT)
	defer stop()

	slots := plugin.NewSlots(o.slots)
	log.Info("starting", "version", version, "resource", o.resource, "slots", o.slots, "dir", o.dir)
	if source := labelSource(o, slots, log); source != nil {
		first, cancel := context.WithTimeout(ctx, 10*time.Second)
		rv, err := source.Sync(first)
		cancel()
		if err != nil {
			log.Warn("cannot read the node yet; starting with --slots", "err", err)
		}
		go source.Follow(ctx, rv)
	}

	p := plugin.New(plugin.Config{
		Dir:             o.dir,
		Socket:          o.socket,
		ResourceName:    o.resource,
		WatchInterval:   o.watchInterval,
		RegisterTimeout: 10 * time.Second,
	}, slots, log)
	if err := p.Run(ctx); err != nil {
		log.Error("failed", "err", err)
		return 1
	}
	return 0
}

// labelSource is the node-label override, or nil when it is off (no node name, no label, or no
// credentials: then --slots holds).
func labelSource(o options, slots *plugin.Slots, log *slog.Logger) *nodeslots.Source {
	if o.nodeName == "" || o.label == "" {
		log.Info("node label override off", "reason", "no --node-name/NODE_NAME or empty --slots-label")
		return nil
	}
	var cfg *rest.Config
	var err error
	if o.kubeconfig != "" {
		cfg, err = clientcmd.BuildConfigFromFlags("", o.kubeconfig)
	} else {
		cfg, err = rest.InClusterConfig()
	}
	if err != nil {
		log.Warn("node label override off: no API credentials", "err", err)
		return nil
	}
	cfg.UserAgent = "simtest-device-plugin/" + version
	client, err := corev1client.NewForConfig(cfg)
	if err != nil {
		log.Warn("node label override off", "err", err)
		return nil
	}
	return &nodeslots.Source{
		Client:  client.Nodes(),
		Node:    o.nodeName,
		Label:   o.label,
		Default: o.slots,
		Slots:   slots,
		Log:     log,
		Retry:   5 * time.Second,
	}
}
