"""Capture real TMCL traffic, read it back, replay it against a virtual module (docs/capture.md).

    from opentmcl.capture import read_capture, replay
    report = replay("run.jsonl", module="TMCM-6212", tolerance=["position=10"])
    print(report.text()); assert report.ok
"""
from .causes import Divergence
from .decode import Decoder
from .format import MAX_CAPTURE_BYTES, MAX_LINE_BYTES, Capture, CaptureError, read_capture
from .outcome import ReplayReport
from .replay import assert_replays, replay
from .snapshot import Snapshot, SnapshotError, snapshot_from_file, snapshot_of
from .tolerance import ReplayError, Tolerance

__all__ = ["MAX_CAPTURE_BYTES", "MAX_LINE_BYTES", "Capture", "CaptureError", "Decoder", "Divergence",
           "ReplayError", "ReplayReport", "Snapshot", "SnapshotError", "Tolerance", "assert_replays",
           "read_capture", "replay", "snapshot_from_file", "snapshot_of"]
