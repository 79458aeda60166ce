package plugin

import (
	"context"
	"log/slog"
	"slices"
	"strings"

	"google.golang.org/grpc"
	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
	pluginapi "k8s.io/kubelet/pkg/apis/deviceplugin/v1beta1"
)

// EnvSlots is the variable Allocate sets in every container that got slots: the comma-separated
// device IDs, e.g. "slot-1". The simulator does not need it; it makes the assignment visible in
// the container (and in `kubectl exec ... env`) for debugging.
const EnvSlots = "SIMTEST_SIMULATOR_SLOTS"

// service answers the kubelet's DevicePlugin calls. It holds no per-connection state, so one
// instance serves every (re)started gRPC server.
type service struct {
	pluginapi.UnimplementedDevicePluginServer

	slots *Slots
	log   *slog.Logger
}

// GetDevicePluginOptions: no PreStartContainer and no GetPreferredAllocation round trips; every
// slot is as good as any other.
func (s *service) GetDevicePluginOptions(context.Context, *pluginapi.Empty) (*pluginapi.DevicePluginOptions, error) {
	return &pluginapi.DevicePluginOptions{}, nil
}

// ListAndWatch sends the slots now and again after every change, until the kubelet hangs up or
// the server stops.
func (s *service) ListAndWatch(_ *pluginapi.Empty, stream grpc.ServerStreamingServer[pluginapi.ListAndWatchResponse]) error {
	for {
		n, changed := s.slots.Get()
		if err := stream.Send(&pluginapi.ListAndWatchResponse{Devices: devices(n)}); err != nil {
			return err
		}
		s.log.Info("advertised slots", "slots", n)
		select {
		case <-changed:
		case <-stream.Context().Done():
			return nil
		}
	}
}

// GetPreferredAllocation is not announced in the options, but answers correctly anyway: the
// devices that must be included, then the lowest free slots, up to the requested size.
func (s *service) GetPreferredAllocation(_ context.Context, req *pluginapi.PreferredAllocationRequest) (*pluginapi.PreferredAllocationResponse, error) {
	resp := &pluginapi.PreferredAllocationResponse{}
	for _, c := range req.ContainerRequests {
		size := int(c.AllocationSize)
		if size > len(c.AvailableDeviceIDs) {
			return nil, status.Errorf(codes.InvalidArgument, "%d slots requested, %d available", size, len(c.AvailableDeviceIDs))
		}
		chosen := slices.Clone(c.MustIncludeDeviceIDs)
		if len(chosen) > size {
			chosen = chosen[:size]
		}
		free := slices.DeleteFunc(slices.Clone(c.AvailableDeviceIDs), func(id string) bool {
			return slices.Contains(chosen, id)
		})
		slices.SortFunc(free, compareSlots)
		chosen = append(chosen, free[:size-len(chosen)]...)
		resp.ContainerResponses = append(resp.ContainerResponses, &pluginapi.ContainerPreferredAllocationResponse{DeviceIDs: chosen})
	}
	return resp, nil
}

// Allocate hands each container its slots as one environment variable. A slot needs no device
// node, mount or annotation: it only counts.
func (s *service) Allocate(_ context.Context, req *pluginapi.AllocateRequest) (*pluginapi.AllocateResponse, error) {
	n, _ := s.slots.Get()
	resp := &pluginapi.AllocateResponse{}
	for _, c := range req.ContainerRequests {
		if err := checkIDs(c.DevicesIds, n); err != nil {
			s.log.Warn("refused allocation", "devices", c.DevicesIds, "err", err)
			return nil, status.Error(codes.InvalidArgument, err.Error())
		}
		ids := strings.Join(c.DevicesIds, ",")
		resp.ContainerResponses = append(resp.ContainerResponses, &pluginapi.ContainerAllocateResponse{
			Envs: map[string]string{EnvSlots: ids},
		})
		s.log.Info("allocated", "devices", ids)
	}
	return resp, nil
}

// PreStartContainer is never requested (PreStartRequired is false); it has nothing to prepare.
func (s *service) PreStartContainer(context.Context, *pluginapi.PreStartContainerRequest) (*pluginapi.PreStartContainerResponse, error) {
	return &pluginapi.PreStartContainerResponse{}, nil
}

// compareSlots orders slot-2 before slot-10; anything else after the slots, by name.
func compareSlots(a, b string) int {
	i, okA := slotIndex(a)
	j, okB := slotIndex(b)
	switch {
	case okA && okB:
		return i - j
	case okA != okB:
		if okA {
			return -1
		}
		return 1
	default:
		return strings.Compare(a, b)
	}
}
