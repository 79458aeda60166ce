"""Recordings: omega-prime (OSI GroundTruth 3.7.0 in MCAP) writer and reader.

Public API: :class:`Recorder` with :class:`RecordingInfo` to write a run, and
:func:`read_trajectories` to read one back for reports.
"""

from simtest_operator.recording.reading import Sample, read_metadata, read_trajectories
from simtest_operator.recording.writing import (
    GROUND_TRUTH_TOPIC,
    MAP_TOPIC,
    Recorder,
    RecordingInfo,
)

__all__ = [
    "GROUND_TRUTH_TOPIC",
    "MAP_TOPIC",
    "Recorder",
    "RecordingInfo",
    "Sample",
    "read_metadata",
    "read_trajectories",
]
