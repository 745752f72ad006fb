"""The live synth's parts: the strike solve, the curve set's slerp fade, the sample ledger, the
note window's sticker on a long stream, and chokes live against their offline twin."""

from __future__ import annotations

import mido
import numpy as np

from livedrummer.body import quat
from livedrummer.body.blend import blend_rows
from livedrummer.body.perform import perform
from livedrummer.body.rig import Rig
from livedrummer.body.sample import sample_poses
from livedrummer.body.skeleton import PARENTS, J
from livedrummer.body.strike import to_local
from livedrummer.kit.vocabulary import PieceKind
from livedrummer.live.ledger import SampleLedger
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.live.track import PoseTrack
from livedrummer.live.window import NoteWindow, WindowParams
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking.online import OnlineSticker
from livedrummer.timeline.events import CONTROL_DTYPE, ControlKind
from livedrummer.timeline.performance import Performance
from services.cli.files import DEMO_MAP
from tests.conftest import MidiWriter

START = 5000.0


def test_to_local_inverts_the_chain_s_world_rotations() -> None:
    rng = np.random.default_rng(1)
    chain = [quat.normalize(rng.normal(size=(5, 4))) for _ in range(4)]
    parent = quat.normalize(rng.normal(size=(5, 4)))
    local = to_local(parent, *chain)
    world = parent
    for q_local, q_world in zip(local, chain, strict=True):
        world = quat.mul(world, q_local)
        assert np.allclose(np.abs(np.sum(world * q_world, axis=-1)), 1.0)
    assert to_local(None, chain[0])[0] is chain[0]


def _bone_lengths(rows: np.ndarray) -> np.ndarray:
    pos = rows["position"].astype(np.float64)
    return np.stack(
        [np.linalg.norm(pos[:, j] - pos[:, PARENTS[j]], axis=-1) for j in range(1, len(PARENTS))],
        -1,
    )


def test_the_cross_fade_keeps_every_bone_s_length(rig: Rig, groove: Performance) -> None:
    # two poses far apart: a stroke's top and its contact, in the same animation
    done = perform(groove, rig, load_note_map(DEMO_MAP))
    st, anim = done.sticking, done.animation
    t = np.linspace(3.0, 4.0, 61)
    rows = sample_poses(anim, st, t)
    tips = rows["position"][:, J["r_tip"]]
    far = int(np.argmax(np.linalg.norm(tips - tips[0], axis=-1)))
    a, b = rows[:1], rows[far : far + 1]
    n = 11
    w = np.linspace(0.0, 1.0, n)
    blended = blend_rows(rig, np.repeat(a, n), np.repeat(b, n), w)
    ref = _bone_lengths(a)[0]
    assert np.abs(_bone_lengths(blended) - ref).max() < 2e-5, "a bone changed length mid-fade"
    # the ends are the poses themselves, the stick tip moves on an arc in between
    tip = J["r_tip"]
    assert np.allclose(blended["position"][0], a["position"][0], atol=2e-5)
    assert np.allclose(blended["position"][-1], b["position"][0], atol=2e-5)
    moved = np.linalg.norm(b["position"][0, tip] - a["position"][0, tip])
    assert moved > 0.05, "the two poses should be far apart for this test"
    # a linear blend of the same two poses would shorten the arm: the test can fail
    lin = a["position"][0] + 0.5 * (b["position"][0] - a["position"][0])
    lin_rows = a.copy()
    lin_rows["position"][0] = lin
    assert np.abs(_bone_lengths(lin_rows)[0] - ref).max() > 1e-3


def test_the_ledger_keeps_a_quarter_second_of_what_was_published() -> None:
    dtype = np.dtype([("time_s", "<f4"), ("v", "<i4")])
    ledger = SampleLedger(dtype, keep_s=0.25)
    step = 1 / 240
    for k in range(2000):  # eight seconds, a chunk held and published per tick
        t = START + k * step
        rows = np.zeros(1, dtype)
        rows["v"] = k
        ledger.hold(np.array([t]), rows, replace=False)
        contact = np.zeros(1, dtype)
        ledger.add_quick(np.array([t]), contact)
        ledger.take_quick()
        ledger.publish(t - step, t, t - 0.03, np.zeros(0))
    times, rows = ledger.samples()
    assert 0.24 <= times[-1] - times[0] <= 0.25 and times.size <= 61
    assert len(ledger.struck()) <= 0.25 / step + 10


def test_the_live_sticker_drops_old_notes_and_decides_as_the_keeping_one(
    rig: Rig, groove: Performance
) -> None:
    on = groove.onsets[groove.onsets["time_s"] < 20.0]
    reps = 8  # the groove played again and again: 8x its notes through one sticker
    span = float(on["time_s"][-1]) + 0.5
    rows = np.concatenate([on] * reps)
    rows["time_s"] += np.repeat(np.arange(reps) * span, on.size)
    keep, drop = (OnlineSticker(rig.kit, 0.03, keep_onsets=k) for k in (True, False))
    a, b = [], []
    for k, row in enumerate(rows):
        a += keep.process(row)
        b += drop.process(row)
        assert drop.provisional(k) == keep.provisional(k), f"note {k}'s provisional limb"
    a += keep.flush()
    b += drop.flush()
    assert a == b, "the same decisions whether old notes are kept or not"
    assert rows.size > 1000 and keep.onsets().size == rows.size
    assert drop.onsets().size < 300, "the live sticker held on to old notes"
    assert drop._original.size <= 512, "its arrays grew with the stream"


def _choke_groove(write_midi: MidiWriter, crash_note: int) -> Performance:
    """Two bars at 120 bpm: hi-hat eighths, kick and snare, a crash on beat 3 of bar 1,
    choked a beat later (a grab, released half a beat after)."""
    msgs: list[mido.Message] = []
    events: list[tuple[int, mido.Message]] = []
    for k in range(16):
        tick = k * 240
        events.append((tick, mido.Message("note_on", channel=9, note=42, velocity=80)))
        if k % 4 == 0:
            events.append((tick, mido.Message("note_on", channel=9, note=36, velocity=100)))
        if k % 4 == 2:
            events.append((tick, mido.Message("note_on", channel=9, note=38, velocity=100)))
    events.append((960, mido.Message("note_on", channel=9, note=crash_note, velocity=120)))
    events.append((1440, mido.Message("polytouch", channel=9, note=crash_note, value=127)))
    events.append((1680, mido.Message("polytouch", channel=9, note=crash_note, value=0)))
    events.sort(key=lambda e: e[0])
    now = 0
    for tick, m in events:
        msgs.append(m.copy(time=tick - now))
        now = tick
    return read_midi_file(write_midi(msgs), load_note_map("roland-td"))


def test_a_choke_stops_the_cymbal_live_as_it_does_offline(rig: Rig, write_midi: MidiWriter) -> None:
    note_map = load_note_map("roland-td")
    crash = next(i for i, p in enumerate(rig.kit.pieces) if p.kind is PieceKind.CRASH)
    crash_note = next(
        n
        for n in range(128)
        if (s := note_map.lookup(n)) is not None
        and (pc := rig.kit.resolve(s.instrument)) is not None
        and pc.name == rig.kit.pieces[crash].name
    )
    perf = _choke_groove(write_midi, crash_note)
    assert perf.controls.size == 2
    choke_s = float(perf.controls["time_s"][0])
    offline = perform(perf, rig, note_map)

    params = SynthParams()
    synth = LiveSynth(rig, params, note_map=note_map)
    onsets = perf.onsets.copy()
    controls = perf.controls.copy()
    onsets["time_s"] += START
    controls["time_s"] += START
    now, end = START - 0.2, START + float(onsets["time_s"][-1] - START) + 0.5
    track = PoseTrack(keep_s=10.0)
    i = c = 0
    while now < end:
        while c < controls.size and controls["time_s"][c] <= now:
            synth.control(controls[c])
            c += 1
        while i < onsets.size and onsets["time_s"][i] <= now:
            synth.process(onsets[i])
            q = synth.take_quick()
            track.add(q.show_s, q.rows)
            i += 1
        b = synth.poses_until(now)
        track.add(b.show_s, b.rows)
        now += 1 / 120
    perf_t = track.show_s - params.delay_s - START
    live = track.rows["swing"][:, crash].astype(np.float64)
    ref_rows = sample_poses(offline.animation, offline.sticking, perf_t, offline.chokes)
    ref = ref_rows["swing"][:, crash].astype(np.float64)
    crash_s = float(perf.onsets["time_s"][perf.onsets["note"] == crash_note][0])
    ringing = (perf_t > crash_s + 0.05) & (perf_t < choke_s)
    after = (perf_t > choke_s) & (perf_t < choke_s + 0.6)
    assert ringing.sum() > 50 and after.sum() > 100
    assert np.abs(ref[ringing]).max() > 0.02, "the crash should swing before its choke"
    assert np.abs(live[ringing] - ref[ringing]).max() < 1e-4
    # exact by design: a choked cymbal's swing is set to rest, not decayed towards it
    assert np.abs(ref[after]).max() == 0.0, "offline, the choke stops the crash"
    assert np.abs(live[after] - ref[after]).max() < 1e-4, "live, the choke stops it too"


def test_the_window_stays_bounded_under_a_flood_and_a_moving_pedal(
    rig: Rig, groove: Performance
) -> None:
    wp = WindowParams(0.03, True, 1.0, 0.025, 4.0, 4.0, max_notes=128, keep_s=0.03)
    window = NoteWindow(rig, wp)
    rate, n = 1000.0, 4000  # four seconds of a flood, then ten of the pedal alone
    rows = np.concatenate([groove.onsets] * (n // groove.onsets.size + 1))[:n].copy()
    rows["time_s"] = START + np.arange(n) / rate
    most = 0
    for k in range(0, n, 10):
        now = float(rows["time_s"][k + 9])
        window.add(rows[k : k + 10])
        window.advance(now)
        window.prune(now - wp.lookahead_s)
        most = max(most, len(window._notes))
    assert most <= wp.max_notes + 10 + rate * wp.lookahead_s, most
    # decided notes far behind the horizon left; none left that a re-send could reach
    content = window.content(now - wp.lookahead_s)
    assert content.contacts_s[0] < now - wp.lookahead_s - wp.keep_s
    pedal = np.zeros((), CONTROL_DTYPE)
    pedal["kind"], pedal["number"] = ControlKind.HIHAT_PEDAL, 4
    for k in range(2000):  # 200 pedal events a second, no notes
        now += 0.005
        pedal["time_s"], pedal["value"] = now, k % 128
        window.control(pedal)
        window.advance(now)
        window.prune(now - wp.lookahead_s)
    assert len(window._notes) == 0
    assert len(window._controls) <= 1.5 * wp.window_s / 0.005 + 1, len(window._controls)


def test_the_track_names_the_sample_after_the_one_it_draws() -> None:
    track = PoseTrack(keep_s=10.0)
    rows = np.zeros(4, [("v", np.float32)])
    track.add(np.array([1.0, 1.004, 1.5, 2.0]), rows)  # a gap, then a quick contact ahead
    got = track.at(1.3)
    assert got is not None and got[0] == 1.004
    assert track.next_after(got[0]) == 1.5 and track.next_after(2.0) is None
