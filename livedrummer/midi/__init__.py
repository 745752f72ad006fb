"""MIDI in: files, byte streams, driver stamps, and what each note number means.

Everything that reads MIDI and turns it into the drum model's words lives here, used
unchanged by the offline file path and the live input daemon:

* :mod:`~livedrummer.midi.smf`: Standard MIDI Files into a performance (mido parses);
* :mod:`~livedrummer.midi.stream`: the incremental byte-stream parser for serial trigger boards;
* :mod:`~livedrummer.midi.decode`: one channel message into onsets and control events;
* :mod:`~livedrummer.midi.notemap`: note maps (note number → instrument and zone per module);
* :mod:`~livedrummer.midi.gm`: the General MIDI note that sounds a stroke (for GM samplers);
* :mod:`~livedrummer.midi.drivertime`: a MIDI driver's delta times anchored on the shared clock.

Limits: MIDI 1.0 only (no MIDI 2.0 UMP); the package imports no I/O (ports and serial lines
are opened by :mod:`services.input`).
"""
