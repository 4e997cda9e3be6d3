"""Calibration of the twin to bench recordings: :func:`calibrate` fits configuration fields (dotted
paths, with bounds) to one or more recordings, with intervals and identifiability warnings.

Modules: :mod:`.params` (fields and bounds), :mod:`.objective` (what a recording can tell),
:mod:`.search` (global then local, parallel, logged and resumable), :mod:`.bootstrap` (intervals from a
block bootstrap over crank turns, ROUGH objectives), :mod:`.uncertainty` (ΔJ and noise intervals,
correlated pairs, flat profiles), :mod:`.report` (outputs). See docs/calibration.md.
"""

from twin.calibration.calibrate import CalibrationOptions, CalibrationResult, FittedParameter, calibrate, overlay
from twin.calibration.params import Parameter, documented_ranges, make_parameters, parse_bounds

__all__ = ["CalibrationOptions", "CalibrationResult", "FittedParameter", "Parameter", "calibrate",
           "documented_ranges", "make_parameters", "overlay", "parse_bounds"]
