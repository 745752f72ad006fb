"""livedrummer: an electronic drum kit or a MIDI file in, a believable 3D drummer out.

The package is pure logic (kit model, events, limb assignment, kinematics, strokes, wire
protocol) on numpy arrays and frozen dataclasses; processes, devices, sockets and windows live
in the top-level ``services`` package and in :mod:`services.cli`.
"""

__version__ = "0.1.0"
