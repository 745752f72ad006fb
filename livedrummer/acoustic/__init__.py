"""Acoustic drums: the percussion recogniser (audio in, onsets out), live and from recordings.

:mod:`.pieces` names the classes a recording is sorted into; :mod:`.spectrum` frames audio
into causal short-time spectra; :mod:`.detector` finds and classifies hits in a mix, offline
(:func:`~.detector.detect`) and online (:class:`~.detector.OnlineDetector`);
:mod:`.multimic` does the same for one microphone per drum; :mod:`.profile` holds a kit's
templates and level calibration; :mod:`.score` counts hits against a MIDI ground truth.
Pure numpy: no audio devices or files here (those are in ``services``).
"""
