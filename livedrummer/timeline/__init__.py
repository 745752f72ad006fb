"""What was played, on one clock: events, performances, the session journal, the clock itself.

* :mod:`~livedrummer.timeline.clock`: the one clock every process reads, injected;
* :mod:`~livedrummer.timeline.events`: onsets and control events (dataclasses and numpy rows);
* :mod:`~livedrummer.timeline.performance`: one file's or one session's events and metadata;
* :mod:`~livedrummer.timeline.journal`: the append-only, CRC-checked session journal format.

Times are seconds (float64) on the shared clock everywhere inside; ticks and driver stamps
are converted at the edge (:mod:`livedrummer.midi`).
"""
