"""Pilot-flown flights (issue 42): stick segments of a log and what each does."""

from tlm_process.pilot.signature import (
    METRICS,
    StickSegment,
    flight_time_s,
    pilot_signature,
    segment_metrics,
    segments_from_rcin,
    segments_from_sidecar,
)

__all__ = ["METRICS", "StickSegment", "flight_time_s", "pilot_signature", "segment_metrics",
           "segments_from_rcin", "segments_from_sidecar"]
