"""What was played, on one clock: events, performances, tempo maps, the clock itself.

* :mod:`~livedrummer.timeline.clock`: the one clock every process reads, injected;
* :mod:`~livedrummer.timeline.events`: onsets and control events (dataclasses and numpy rows);
* :mod:`~livedrummer.timeline.performance`: one file's or one session's events and metadata;
* :mod:`~livedrummer.timeline.stats`: what a reader counted of its source, kept or not;
* :mod:`~livedrummer.timeline.tempo`: the tempo map and beat grid (ticks become seconds once).

Times are seconds (float64) on the shared clock everywhere inside; ticks and driver stamps
are converted at the edge (:mod:`livedrummer.midi`). The package sits below ``midi`` and
``protocol``, which read into and write out of its records; the session journal's format is
:mod:`livedrummer.protocol.journal`.
"""
