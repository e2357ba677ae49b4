"""Streaming to Dynamixel servos: bus abstraction, the dynamixel-sdk bus, a virtual Protocol 2.0
servo chain on a pseudo-terminal, calibration, the safety guard, the fixed-rate streamer and its
telemetry. See ``docs/hardware.md``."""
