"""The input daemon (``livedrummer input``): a kit, a trigger board, a file or a remote site in;
onsets and controls out over ZeroMQ in the :mod:`livedrummer.protocol` schema; every session
journaled (:mod:`services.input.journal`).

Modules: ``base`` (the source interface), one module per backend (``midiport``,
``serialport``, ``fileplayer``, ``remote``), ``daemon`` (sockets, publishing, journaling,
reconnects). Backends import their device library only when chosen, so ``--file`` works on a
machine without ALSA or a serial driver.
"""
