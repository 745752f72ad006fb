"""Drum sounds for video export: a synthesized, velocity-layered kit and an offline mixer.

Pure numpy: :mod:`~livedrummer.audio.synth` makes the samples, :mod:`~livedrummer.audio.mix`
places them at the onsets of a performance in one stereo buffer. No files, no downloads.
"""
