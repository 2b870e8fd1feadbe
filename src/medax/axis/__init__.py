"""numpy-only: the paper's section 2, tracing the medial axis of a 4-sided region."""

from medax.axis.medial import METHODS, trace_axis
from medax.axis.result import MedialAxis, WorkCounts

__all__ = ["METHODS", "MedialAxis", "WorkCounts", "trace_axis"]
