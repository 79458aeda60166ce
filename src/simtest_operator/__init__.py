"""simtest-operator: Kubernetes-native, scenario-based simulation testing for automated driving."""

__version__ = "0.1.0"
