"""cartoonface: talking cartoon faces from a face model, speech and its transcript.

The data flows one way (see docs/ARCHITECTURE.md):
inputs -> face model and speech analysis -> timeline -> frames -> SVG -> pages.
"""

__version__ = "0.1.0"
