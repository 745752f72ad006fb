"""Live pipeline logic: the online synthesizer, prediction, pose streams and their measures.

Pure code (numpy, dataclasses, no sockets): the services in ``services/synth`` and
``services/display/live.py`` wrap it with I/O, and the tests drive it with a stepped clock.
"""
