"""Each test marked ``e2e`` or ``gpu`` from what its own code reaches, with no list to keep.

Why this shape. A marker written by hand on ~1,000 tests drifts the day a unit test grows a
subprocess, and a module-wide ``pytestmark`` throws a file's unit tests out of the fast subset
with its one end-to-end test. So :func:`marks_of` reads a test module's syntax tree: a test is
``e2e`` when its function, or any function, class or fixture of its module that it names
(followed transitively), or any fixture it asks for, names something that starts a real
process, socket, JACK server or window (:data:`E2E_NAMES`, :data:`E2E_FIXTURES`, or a CLI
``main([...])`` of a command in :data:`E2E_COMMANDS`); ``gpu`` when it makes an OpenGL context
(headless EGL on Mesa's llvmpipe without a GPU: :data:`GPU_NAMES`, :data:`GPU_FIXTURES`,
:data:`GPU_COMMANDS`). ``slow`` is measured, not read: :data:`SLOW` names the pure tests that
take seconds, by file name and test name, so it holds when the files move and does not touch
files other people are editing. The conftest's collection hook adds the marks; a mark written on
a test (``pytestmark``, a decorator) is kept, so a case the names miss is marked by hand.

Limits: static, by name. The library is not followed (it opens nothing, by rule), nor a module
imported whole (``mod.fn()``); a test that reaches a process only that way stays unmarked, and
``make test-fast`` timing its run is the check on that. Names are matched wherever they appear in a function, even in a
branch that is not taken.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable
from functools import cache
from pathlib import Path

#: Names whose use means a real process, socket, JACK server or window.
E2E_NAMES = frozenset(
    {
        "subprocess",
        "Popen",
        "multiprocessing",
        "zmq",
        "socket",
        "dummy_jack",
        "jack_env",
        "xvfb",
        "InputDaemon",
        "SynthService",
        "LiveDisplay",
        "StageDisplay",
        "Supervisor",
        "Service",
        "StreamReceiver",
        "RemoteSource",
        "MidiPortSource",
        "SerialSource",
        "request_ready",
        "connect",
        "bind",
        "run_installed",
    }
)
#: Fixtures that start such a thing.
E2E_FIXTURES = frozenset({"jack_server", "jack_default_server", "jack_rig_server", "installed"})
#: ``livedrummer`` subcommands that start processes, sockets or windows when run in a test.
E2E_COMMANDS = frozenset(
    {"up", "input", "synth", "display", "relay", "practice", "demo", "monitor", "stage-display"}
)
#: Names whose use means an OpenGL context.
GPU_NAMES = frozenset(
    {"headless_context", "Renderer", "HeadlessSurface", "VideoWriter", "AvatarGl", "gl_ok"}
)
GPU_FIXTURES = frozenset({"gl_ok"})

#: The pure tests that take seconds (a corpus, a fuzz or property run, a long performance
#: animated): ``file::test`` (every parameter of it), by the file's name, so that the list
#: holds wherever the file lives. Measured by ``pytest -m "not e2e" --durations=80`` (the
#: tests of 3 s and more on a busy two-core machine).
SLOW = frozenset(
    {
        "test_acoustic.py::test_shipped_profile_is_the_soundfonts",
        "test_beat.py::test_a_flood_keeps_each_update_bounded",
        "test_body_check.py::test_corpus_sample_lands",
        "test_corpus.py::test_every_groove_file_ingests_exactly",
        "test_fuzz_midifile.py::test_absurd_note_counts_are_bounded",
        "test_fuzz_midifile.py::test_mutated_corpus_files_end_in_named_errors_or_bounded_results",
        "test_live_parts.py::test_a_choke_stops_the_cymbal_live_as_it_does_offline",
        "test_live_parts.py::test_the_window_stays_bounded_under_a_flood_and_a_moving_pedal",
        "test_live_style.py::test_a_preset_change_while_playing_moves_no_joint_faster_than_playing",
        "test_midifile.py::test_random_bytes_never_escape_as_other_exceptions",
        "test_midistream.py::test_property_chunking_is_invisible",
        "test_midistream.py::test_property_garbage_never_hides_valid_messages",
        "test_midistream.py::test_property_valid_stream_round_trips",
        "test_protocol.py::test_fuzz_pose_format_descriptions",
        "test_protocol.py::test_sequence_tracker_counts_exactly_what_was_dropped",
        "test_render_export.py::test_video_colours_match_the_rendered_frames",
        "test_render_export.py::test_video_frames_audio_and_onsets_line_up",
        "test_render_motion.py::test_transport_position_stays_in_range",
        "test_render_overlay.py::test_render_command_draws_the_overlays",
        "test_render_span.py::test_bars_render_their_frames",
        "test_stage.py::test_render_stage_draws_every_drummer_in_its_place",
        "test_stage_layout.py::test_render_stage_honours_end_and_tail",
        "test_sticking_gmd.py::test_optimal_beats_the_seeds_on_real_performances",
        "test_sticking_path.py::test_sheet_and_animation_agree_note_for_note_on_20_gmd_files",
        "test_synth.py::test_a_hit_s_contact_goes_out_on_arrival_only_when_provisional",
        "test_synth.py::test_a_quick_contact_leaves_the_synth_as_it_was",
        "test_synth.py::test_contacts_land_on_the_offline_contact_at_onset_plus_delay",
        "test_synth.py::test_every_hit_gets_its_contact_on_arrival_on_its_target",
        "test_synth.py::test_prediction_raises_the_stick_before_regular_hits",
    }
)
GPU_COMMANDS = frozenset({"render", "avatar", "export"})


def _called_commands(node: ast.AST) -> set[str]:
    """The first word of every ``main(["word", ...])`` call under ``node``."""
    out = set()
    for call in ast.walk(node):
        if (
            isinstance(call, ast.Call)
            and isinstance(call.func, ast.Name)
            and call.func.id == "main"
            and call.args
            and isinstance(call.args[0], ast.List)
            and call.args[0].elts
            and isinstance(first := call.args[0].elts[0], ast.Constant)
            and isinstance(first.value, str)
        ):
            out.add(first.value)
    return out


def _names(node: ast.AST) -> set[str]:
    """Every identifier ``node`` uses: names, attribute names, its arguments' names."""
    out: set[str] = set()
    for n in ast.walk(node):
        if isinstance(n, ast.Name):
            out.add(n.id)
        elif isinstance(n, ast.Attribute):
            out.add(n.attr)
        elif isinstance(n, ast.arg):
            out.add(n.arg)
        elif isinstance(n, ast.alias):
            out.add((n.asname or n.name).split(".")[0])
    return out


REPO = Path(__file__).resolve().parent.parent


def _source_of(module: str) -> Path | None:
    """The file of a test or process module (``tests.x``, ``services.x.y``); the library is
    pure by rule (tests/test_layers.py) and is not followed."""
    if module.split(".")[0] not in ("tests", "services"):
        return None
    base = REPO.joinpath(*module.split("."))
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


@cache
def _table(
    path: Path,
) -> tuple[dict[str, set[str]], dict[str, set[str]], dict[str, tuple[Path, str]]]:
    """Of one module: each definition's own marks, the module's definitions it names, and the
    names it imports from other test or process modules (name → (file, name there))."""
    tree = ast.parse(path.read_text(), str(path))
    defs: dict[str, ast.AST] = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            defs[node.name] = node
        if isinstance(node, ast.ClassDef):
            for sub in node.body:
                if isinstance(sub, ast.FunctionDef | ast.AsyncFunctionDef):
                    defs[f"{node.name}.{sub.name}"] = sub
    # Module-level names bound by assignment count as what their value uses.
    values = {
        t.id: node.value
        for node in tree.body
        if isinstance(node, ast.Assign)
        for t in node.targets
        if isinstance(t, ast.Name)
    }
    try:  # a package's __init__ and its modules: the same base for relative imports
        package = list(path.relative_to(REPO).with_suffix("").parts[:-1])
    except ValueError:  # a file outside the checkout (a test of this module)
        package = []
    imported: dict[str, tuple[Path, str]] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            source = _source_of(module)
            if source is not None and source != path:
                for a in node.names:
                    imported[a.asname or a.name] = (source, a.name)
    direct: dict[str, set[str]] = {}
    uses: dict[str, set[str]] = {}
    for name, node in defs.items():
        names = _names(node)
        for var in names & values.keys():
            names |= _names(values[var])
        commands = _called_commands(node)
        marks = set()
        if names & E2E_NAMES or commands & E2E_COMMANDS:
            marks.add("e2e")
        if names & GPU_NAMES or commands & GPU_COMMANDS:
            marks.add("gpu")
        direct[name] = marks
        uses[name] = names - {name}
    return direct, uses, imported


_seen: dict[tuple[Path, str], frozenset[str]] = {}


def _marks(path: Path, name: str) -> frozenset[str]:
    """The marks of definition ``name`` of ``path``, following what it names: definitions of
    its module and names imported from other test and process modules, transitively."""
    key = (path, name)
    if key in _seen:
        return _seen[key]
    _seen[key] = frozenset()  # a loop adds nothing
    direct, uses, imported = _table(path)
    marks = set(direct.get(name, ()))
    for other in uses.get(name, ()):
        if other in direct:
            marks |= _marks(path, other)
        elif other in imported:
            marks |= _marks(*imported[other])
    _seen[key] = frozenset(marks)
    return _seen[key]


def marks_of(path: Path, qualname: str, fixtures: Iterable[str]) -> frozenset[str]:
    """The marks (``e2e``, ``gpu``; ``slow`` from :data:`SLOW`) of the test ``qualname``
    (``test_x`` or ``TestY.test_x``) in ``path`` that asks for ``fixtures`` (all of them,
    the conftest's too)."""
    fixtures = set(fixtures)
    marks = set(_marks(path, qualname))
    if f"{path.name}::{qualname.rpartition('.')[2]}" in SLOW:
        marks.add("slow")
    for fixture in fixtures:
        marks |= _marks(path, fixture)
    if fixtures & E2E_FIXTURES:
        marks.add("e2e")
    if fixtures & GPU_FIXTURES:
        marks.add("gpu")
    return frozenset(marks)
