"""The synth service: onsets in over ZeroMQ, poses out (see :mod:`services.synth.service`)."""
