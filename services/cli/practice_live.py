"""``livedrummer practice REF.mid --virtual NAME | --midi PORT | --serial DEV``: play along.

Counts in (``--count-in BARS``), then plays the reference's beat grid as a click (accented
downbeats; ``--click-sound``, ``--click-level``; :mod:`services.practice.click`) at the
practised tempo (``--tempo SCALE`` or ``--bpm B``) over the whole reference or ``--bars
BAR:BAR`` (loop A-B; not spelled ``--loop``: ``input --loop`` is a flag, and one option name
takes one kind of value in every command), for ``--passes N``. Hits come from the same
sources as ``calibrate`` (through :func:`~.common.kit_source`; their times are the driver
stamps on the shared clock, plus calibration.toml's ``input_ms``) and are decoded with
``--take-map`` (the kit's note map). A pass cut short (``--seconds``, Ctrl-C) is judged on the
notes due a window before the stop, without the hits after them that match none, and marked
``partial`` (its take, scored later against the whole pass, counts the rest as missed).

Each hit gets a provisional line at once (:mod:`livedrummer.practice.live`: early/late meter,
streak, running accuracy); when a pass is over (its end plus the window) all its hits are judged
with :func:`~livedrummer.practice.match.match_take` against the pass's notes
(:mod:`livedrummer.practice.plan`), doubled notes merged first (one note twice within 1 ms, as
every MIDI file is read, and the hits' times put on the take file's tick grid, so the take
file holds what was judged), and its summary printed,
stored in the practice database (``--no-save`` not to), written as a take (``--take
FILE.mid``; pass k>1 as FILE-passK.mid) and as a report (``--report FILE.html``, likewise).
``practice score REF FILE.mid`` with the same ``--bars/--tempo/--bpm`` judges the take file
exactly as the pass was judged.

Drills: ``--pieces`` (time check of selected pieces), ``--quiet-count ON:OFF`` (the click drops
out for OFF bars after ON bars), ``--ramp BPM`` with ``--ramp-target``/``--ramp-min-accuracy``
(auto up/down: a count-in bar at the new tempo between passes).

The drummers (:mod:`.practice_show`): with a screen, or ``--headless``, the rig runs an input
daemon, a synth and a live display as ``up`` does and reads its hits from the daemon's stream
(the same driver stamps); the display draws the player's drummer, the teacher (``--teacher``)
and this readout, which the rig sends it. ``--no-window``, or no screen, is the terminal alone.

Scripting: ``--no-sound`` shows the clicks as nothing (no audio device needed); ``--json``
prints one JSON line per planned pass (its notes and clicks on the shared clock, so a scripted
player can follow), per hit, per hit no pass owns (``stray``: in the count-in, or after its
pass was judged; the terminal counts them at the end), per pass result (the ``practice score
--json`` object) and a last ``done`` line (with ``stray_hits`` and ``doubled_hits``: hits the
kit's decoder dropped as the same note and velocity on one driver stamp, which only a burst
delivered in one JACK cycle makes; on stderr too).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .devices import add_api_option
from .files import add_channel_option, add_map_option


def add_live_options(p: argparse.ArgumentParser) -> None:
    from .practice_setup import add_db_option, add_judge_options, add_pass_options

    p.add_argument("reference", type=Path, metavar="REF.mid", help="the reference to play along")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--midi", metavar="PORT", help="MIDI input port (name or substring)")
    src.add_argument("--virtual", metavar="NAME", help="open a virtual MIDI input port NAME")
    src.add_argument("--serial", metavar="DEV", help="serial device sending raw MIDI bytes")
    p.add_argument("--baud", type=int, default=31_250, help="serial baud rate (default 31250)")
    add_api_option(p)
    add_map_option(p)
    p.add_argument(
        "--take-map",
        default="roland-td",
        metavar="MAP",
        help="note map of the kit's hits (default roland-td)",
    )
    add_channel_option(p)
    add_judge_options(p)
    add_pass_options(p)
    p.add_argument(
        "--passes",
        type=int,
        metavar="N",
        help="passes (default 1; 4 with --bars; until a stop with --ramp)",
    )
    p.add_argument(
        "--count-in",
        type=int,
        default=1,
        metavar="BARS",
        help="bars of click before the first pass (default 1)",
    )
    p.add_argument("--click-level", type=float, default=0.5, help="click volume 0..1")
    p.add_argument(
        "--click-sound",
        choices=("beep", "wood", "cowbell"),
        default="beep",
        help="click sound (default beep)",
    )
    p.add_argument(
        "--quiet-count",
        metavar="ON:OFF",
        help="click ON bars, then OFF bars silent (default: always on)",
    )
    p.add_argument(
        "--ramp",
        type=float,
        metavar="BPM",
        help="auto up/down: tempo change per pass (default: none)",
    )
    p.add_argument(
        "--ramp-target",
        type=float,
        metavar="BPM",
        help="stop after the pass at this tempo (default: none)",
    )
    p.add_argument(
        "--ramp-min-accuracy",
        type=float,
        metavar="PCT",
        help="stop once a pass's accuracy is below PCT (default: none)",
    )
    p.add_argument("--no-sound", action="store_true", help="no click sound (scripted use)")
    p.add_argument("--json", action="store_true", help="print JSON lines (see above)")
    p.add_argument(
        "--take",
        type=Path,
        metavar="FILE.mid",
        help="write each pass's hits as a take (default: none)",
    )
    p.add_argument(
        "--report",
        type=Path,
        metavar="FILE.html",
        help="write each pass's HTML report (default: none)",
    )
    p.add_argument("--no-save", action="store_true", help="keep nothing in the practice database")
    add_db_option(p)
    p.add_argument(
        "--seconds",
        type=float,
        metavar="S",
        help="stop after S seconds (default: when the passes are done)",
    )
    from .practice_show import add_show_options

    add_show_options(p)


#: A pass is judged once a read that began this long after the last hit it can own is done,
#: so a hit stamped just before that moment but queued just after it (the driver's stamp and
#: its queueing are not one instant) is still the pass's. The moment is taken before the read,
#: not after it: a rig starved of the CPU between a read and that check would otherwise close
#: the pass on a hit still waiting in the queue, and count it outside every pass.
SETTLE_S = 0.05
#: The same with the drummers shown, where the hits come through the input daemon (one more
#: process to be scheduled and a socket between the stamp and the rig): a loaded machine
#: delays that hop by tens of ms. A hit later still is a ``stray`` line, not lost silently.
BUS_SETTLE_S = 0.25
#: Headless, the drummers are drawn this long after the last pass, so the frames and the
#: recording end on its summary (a window keeps it until it is closed).
SUMMARY_HOLD_S = 3.0


def numbered(path: Path, k: int) -> Path:
    """Pass ``k``'s file: ``path`` itself for pass 1, ``stem-passK.suffix`` after."""
    return path if k == 1 else path.with_name(f"{path.stem}-pass{k}{path.suffix}")


@dataclass
class Pass:
    number: int
    start_s: float  # shared clock
    scale: float
    bpm: float
    notes: Any  # ONSET_DTYPE on the pass clock
    length_s: float
    readout: Any
    hits: list[tuple[Any, ...]] = field(default_factory=list)  # ONSET records, pass clock
    result: dict[str, Any] | None = None


def run_live(args: argparse.Namespace) -> int:
    import numpy as np

    from livedrummer.errors import ConfigError, LivedrummerError
    from livedrummer.live.calibration import Calibration
    from livedrummer.midi.decode import MessageDecoder, merge_doubled_notes
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.practice.grade import summary
    from livedrummer.practice.live import LiveReadout
    from livedrummer.practice.match import PIECES, match_take, piece_codes
    from livedrummer.practice.plan import (
        Ramp,
        count_in,
        first_bpm,
        pass_bounds,
        pass_clicks,
        pass_length_s,
        pass_notes,
    )
    from livedrummer.timeline.clock import MonotonicClock
    from livedrummer.timeline.events import ONSET_DTYPE, Onset

    from ..practice.take import on_take_grid
    from .devices import kit_source
    from .files import read_performance
    from .practice_setup import judge_settings, pass_setup, summary_lines
    from .practice_show import Show, check_show, show_mode, show_settings

    window_ms, pieces, level = judge_settings(args)
    ref, _ = read_performance(args, args.reference)
    if not ref.onsets.size:
        raise LivedrummerError(f"{args.reference}: no drum notes to play along to")
    seg, scale = pass_setup(args, ref)
    quiet = None
    if args.quiet_count is not None:
        parts = args.quiet_count.split(":")
        if len(parts) != 2 or not all(x.isdigit() and int(x) > 0 for x in parts):
            raise ConfigError(f"--quiet-count {args.quiet_count}: expected ON:OFF bars, e.g. 3:1")
        quiet = (int(parts[0]), int(parts[1]))
    if not 0 <= args.count_in <= 8:
        raise ConfigError(f"--count-in {args.count_in}: expected 0..8 bars")
    if not 0.0 <= args.click_level <= 1.0:
        raise ConfigError(f"--click-level {args.click_level:g}: expected 0..1")
    ramp = None
    if args.ramp is not None:
        ramp = Ramp(args.ramp, args.ramp_target, args.ramp_min_accuracy)
    passes_max = args.passes or (1 if args.bars is None and ramp is None else 4)
    if ramp is not None and args.passes is None:
        passes_max = 100
    if not 1 <= passes_max <= 1000:
        raise ConfigError(f"--passes {passes_max}: expected 1..1000")
    base_bpm = first_bpm(ref.grid, seg)
    window_s = window_ms / 1e3
    settings = show_settings(args)  # the loop, and the drummers' processes, use these
    note_map = load_note_map(settings.note_map)
    clock = MonotonicClock()
    mode = show_mode(args)
    check_show(args, mode)
    source: Any = kit_source(args, clock, MessageDecoder(note_map))  # checked: one line if absent
    show = None
    if mode == "none":
        why = "--no-window" if args.no_window else "no screen ($DISPLAY)"
        print(f"practice: terminal readout only ({why})", file=sys.stderr, flush=True)
    else:
        shown = "in a window" if mode == "window" else f"off screen into {args.frames_dir}/"
        print(
            f"practice: the drummers {shown} (teacher {args.teacher})", file=sys.stderr, flush=True
        )
        show = Show(args, mode, settings)
        source = show.bus
    input_s = Calibration.load().input_ms / 1e3
    player = None
    if not args.no_sound:
        from ..practice.click import ClickPlayer

        try:
            player = ClickPlayer(args.click_sound, args.click_level)
        except Exception as exc:  # PortAudio has many ways to fail; the rig still works
            print(f"practice: no sound ({exc}); playing without a click", file=sys.stderr)
    notes_once = pass_notes(ref.onsets, seg, 1.0)["time_s"]
    first_note = float(notes_once.min()) if notes_once.size else 0.0
    last_note = float(notes_once.max()) if notes_once.size else seg.end_s - seg.start_s

    def emit(obj: dict[str, Any]) -> None:
        print(json.dumps(obj), flush=True)

    def plan(number: int, start_s: float, sc: float, bars_in: int) -> Pass:
        notes = pass_notes(ref.onsets, seg, sc)
        clicks, accents = pass_clicks(ref.grid, seg, sc, quiet)
        cin, cacc = count_in(ref.grid, seg, sc, bars_in)
        times = np.concatenate([cin, clicks]) + start_s
        acc = np.concatenate([cacc, accents])
        if player is not None:
            player.schedule(times, acc)
        clicked.append((times, acc))
        codes = piece_codes(notes)
        judged = np.ones(codes.size, bool) if pieces is None else np.isin(codes, list(pieces))
        readout = LiveReadout(notes["time_s"][judged], codes[judged], window_ms, level)
        ps = Pass(number, start_s, sc, base_bpm * sc, notes, pass_length_s(seg, sc), readout)
        if show is not None:
            show.readout.send(
                {
                    "plan": {
                        "pass": number,
                        "start_s": start_s,
                        "scale": sc,
                        "bpm": ps.bpm,
                        "bars": [seg.first_bar, seg.last_bar],
                        "seg_start_s": seg.start_s,
                        "seg_end_s": seg.end_s,
                        "window_ms": window_ms,
                        "level_ms": level.window_ms,
                        "teacher": args.teacher,
                    }
                }
            )
        if args.json:
            emit({"pass": number, "start_s": start_s, "bpm": round(ps.bpm, 3), "scale": sc,
                  "bars": [seg.first_bar, seg.last_bar], "length_s": ps.length_s,
                  "notes": [[start_s + float(r["time_s"]), int(r["note"]), int(r["velocity"])]
                            for r in notes],
                  "clicks_s": times.tolist()})  # fmt: skip
        else:
            wait = start_s - clock.now()
            print(
                f"pass {number}: bars {seg.first_bar}-{seg.last_bar} at {ps.bpm:.1f} bpm, "
                f"{notes.size} notes; starts in {wait:.1f} s",
                flush=True,
            )
        return ps

    def bar_s(sc: float) -> float:
        cin, _ = count_in(ref.grid, seg, sc, 1)
        return float(-cin[0]) if cin.size else 2.0 / sc

    planned: list[Pass] = []
    finished: list[Pass] = []
    heard: list[tuple[Any, ...]] = []  # every hit as stamped (shared clock): --video's track
    clicked: list[tuple[Any, Any]] = []  # every click planned (shared clock, accents): likewise
    reports: list[tuple[Pass, dict[str, Any], Any]] = []

    def finish(p: Pass, due_s: float | None) -> dict[str, Any]:
        """Judge pass ``p`` (only its notes due by ``due_s`` when it was cut short), print,
        keep and queue its report."""
        hits = np.array(p.hits, dtype=ONSET_DTYPE)
        hits = hits[np.argsort(hits["time_s"], kind="stable")]
        hits["time_s"] = on_take_grid(hits["time_s"])  # judged as its take file holds it
        hits = merge_doubled_notes(hits)
        notes = p.notes if due_s is None else p.notes[p.notes["time_s"] <= due_s]
        matching = match_take(notes, hits, window_ms, pieces)
        if due_s is not None:  # a hit after the last note judged, left over: not counted
            early = matching.played_s[matching.extra] <= due_s
            matching = dataclasses.replace(matching, extra=matching.extra[early])
        result = summary(matching, level)
        result.update(
            reference=str(args.reference),
            pass_number=p.number,
            bpm=round(p.bpm, 3),
            bars=[seg.first_bar, seg.last_bar],
            partial=due_s is not None,
            take=str(numbered(args.take, p.number)) if args.take else f"live pass {p.number}",
        )
        p.result = result
        finished.append(p)
        _keep(args, p, result, hits)
        if args.report is not None:
            reports.append((p, result, matching))
        if show is not None:
            show.readout.send({"summary": {"pass": p.number, "lines": summary_lines(result)}})
        if args.json:
            emit({"pass_result": p.number, **result})
        else:
            cut = f", stopped {due_s:.1f} s in" if due_s is not None else ""
            print(f"pass {p.number} ({p.bpm:.1f} bpm{cut}):", flush=True)
            for text in summary_lines(result):
                print(f"  {text}", flush=True)
        return result

    settle_s = SETTLE_S if show is None else BUS_SETTLE_S
    stray = 0
    stopped = ""
    try:
        if show is not None:
            show.start()  # ready: the drummer is drawn (the teacher waits for the first plan)
        source.open()
        started = clock.now()
        first = clock.now() + 0.5 + args.count_in * bar_s(scale)
        planned.append(plan(1, first, scale, args.count_in))
        if ramp is None:
            for k in range(2, passes_max + 1):
                prev = planned[-1]
                planned.append(plan(k, prev.start_s + prev.length_s, scale, 0))
        while True:
            now = clock.now()
            if args.seconds is not None and now - started >= args.seconds:
                stopped = "--seconds"
                break
            if show is not None and not show.tick(now):
                stopped = "window closed"
                break
            bounds = pass_bounds(
                [p.start_s for p in planned],
                [p.length_s for p in planned],
                first_note,
                last_note,
                [p.scale for p in planned],
                window_s,
            )
            # Taken before the read: every hit stamped before ``cut`` is in the source's queue
            # by then, so this read has it; a pass ends only on a ``cut`` past its close (see
            # SETTLE_S), never on a clock read after a stall that let a hit in behind the read.
            cut = clock.now()
            for event in source.read(0.002):
                if not isinstance(event, Onset):
                    continue
                heard.append(event.to_record())
                t = event.time_s + input_s
                owner = next(
                    (
                        p
                        for p, (lo, hi) in zip(planned, bounds, strict=True)
                        if lo <= t < hi and p.result is None
                    ),
                    None,
                )
                if owner is None:
                    stray += 1
                    if args.json:  # no hit goes unreported: outside every open pass's span
                        emit(
                            {
                                "stray": {
                                    "time_s": round(t - planned[0].start_s, 6),
                                    "note": event.note,
                                }
                            }
                        )
                    continue
                rec = list(event.to_record())
                rec[0] = t - owner.start_s
                owner.hits.append(tuple(rec))
                code = int(piece_codes(np.array([tuple(rec)], dtype=ONSET_DTYPE))[0])
                if pieces is not None and code not in pieces:
                    continue  # not judged (--pieces): kept for the wrong-piece step only
                line = owner.readout.process(rec[0], code)
                if show is not None:
                    show.readout.send(
                        {
                            "hit": {
                                "pass": owner.number,
                                "time_s": line.time_s,
                                "piece": PIECES[line.piece],
                                "offset_ms": line.offset_ms,
                                "on_time": line.on_time,
                                "streak": line.streak,
                                "accuracy_pct": line.accuracy_pct,
                            }
                        }
                    )
                if args.json:
                    emit(
                        {
                            "hit": {
                                "pass": owner.number,
                                "time_s": round(line.time_s, 6),
                                "piece": PIECES[line.piece],
                                "offset_ms": line.offset_ms,
                                "on_time": line.on_time,
                                "streak": line.streak,
                                "accuracy_pct": round(line.accuracy_pct, 3),
                            }
                        }
                    )
                else:
                    print(f"  {line.text()}", flush=True)
            for p, (_, hi) in zip(list(planned), bounds, strict=True):
                if p.result is not None or cut < hi + settle_s:
                    continue
                result = finish(p, None)
                if ramp is not None and p.number < passes_max:
                    nxt = ramp.next_bpm(p.bpm, result["accuracy_pct"])
                    if nxt is not None and nxt > 0:
                        sc = nxt / base_bpm
                        start = clock.now() + 0.3 + bar_s(sc)
                        planned.append(plan(p.number + 1, start, sc, 1))
            if len(finished) == len(planned) and (
                ramp is None or len(planned) >= passes_max or planned[-1].result is not None
            ):
                break
        if show is not None and not stopped:  # the last pass's summary stays on screen
            hold = SUMMARY_HOLD_S if show.mode == "headless" else math.inf
            until = clock.now() + hold
            if args.seconds is not None:
                until = min(until, started + args.seconds)
            if until == math.inf:
                print(
                    "practice: done; the summary stays in the window until you close it (Q)",
                    file=sys.stderr,
                    flush=True,
                )
            while clock.now() < until and show.tick(clock.now()):
                time.sleep(0.05)
    except KeyboardInterrupt:
        stopped = "interrupted"
    finally:
        if player is not None:
            player.close()
        source.close()
        if show is not None:
            show.close()
    stats = source.decode_stats()
    if stats is not None and stats.unknown_notes:  # a keyboard's keys outside the drum map
        listed = ", ".join(f"note {k} x{v}" for k, v in sorted(stats.unknown_notes.items()))
        print(
            f"practice: hits the map {note_map.name} does not know (not judged): {listed}",
            file=sys.stderr,
        )
    doubled = 0 if stats is None else stats.duplicates_removed
    if doubled:  # the decoder's "double events": the same note and velocity on one stamp
        print(
            f"practice: {doubled} hits dropped as doubled (the same note and velocity at the "
            f"same driver time as the one before; not judged)",
            file=sys.stderr,
        )
    end = clock.now()
    for p in planned:  # a pass cut short: judged on the notes due before the stop
        if p.result is None and p.start_s < end and p.hits:
            finish(p, end - p.start_s - window_s)
    if show is not None and args.video is not None:
        from .practice_show import add_drum_track

        wrote = add_drum_track(settings, args, np.array(heard, dtype=ONSET_DTYPE), clicked)
        print(wrote, file=sys.stderr if args.json else sys.stdout, flush=True)
    for p, result, matching in reports:  # after the session: a report takes seconds to draw
        from .practice_out import write_take_report

        where = numbered(args.report, p.number)
        write_take_report(where, result, ref, matching, seg, p.scale)
        if not args.json:
            print(f"report: {where}")
    if args.json:
        emit(
            {
                "done": True,
                "passes": len(finished),
                "stray_hits": stray,
                "doubled_hits": doubled,
                "stopped": stopped or None,
            }
        )
    else:
        why = f" ({stopped})" if stopped else ""
        print(f"practice: {len(finished)} passes{why}; {stray} hits outside any pass")
    return 0


def _keep(args: argparse.Namespace, p: Pass, result: dict[str, Any], hits: Any) -> None:
    """Write the pass's take and store it (see the module docstring); both take milliseconds."""
    if args.take is not None:
        from ..practice.take import write_take

        write_take(numbered(args.take, p.number), hits)
    if not args.no_save:
        from ..practice.store import PracticeStore

        with PracticeStore.open(args.db) as store:
            result["session_id"] = store.add(result, kind="live")
