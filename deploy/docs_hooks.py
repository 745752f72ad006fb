"""MkDocs hook: the documentation pages that are generated, so that they cannot go stale.

Two references are written from the code at every ``mkdocs build`` (``make docs``,
``tests/test_docs.py``), never kept as files in ``docs/``:

- ``reference/cli.md`` from the argparse parsers of :mod:`services.cli` (every subcommand, every
  nested subcommand, every option with its help as ``--help`` prints it, defaults included;
  options hidden from ``--help``, the former spellings, stay hidden here too);
- ``reference/wire.md`` from :mod:`livedrummer.protocol.spec` (the header layout, the protocol
  version, every kind with its payload, the flags, streams, gap reasons, the HELLO keys, the row
  dtypes field by field and the codes their fields index).

Why a hook and not a script that writes into ``docs/``: the pages exist only in the build, so a
stale copy can be neither committed nor read; ``mkdocs build --strict`` fails if generating
one raises. Why here (``deploy/``) and not in the package: it is a build tool of the
repository; the wheel ships ``livedrummer`` only. The one thing the code does not say, a kind's
meaning in words, is the table :data:`KIND_MEANING` below; a kind missing from it stops the
build, so a new kind cannot be left undocumented.

Limits: the help text is argparse's, written once per option; a subcommand's long description
is its parser's ``description`` (often its one-line summary).
"""

from __future__ import annotations

import argparse
import ast
import os
import re
import struct
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

#: What each message kind is for, the one place the wire reference says it in words.
KIND_MEANING: dict[str, str] = {
    "HELLO": "a client's greeting on a control socket: who it is, what it sends",
    "READY": "the service's answer, sent once it is serving (same JSON as HELLO)",
    "ONSET": "onsets (strokes) of one input daemon, in time order",
    "CONTROL": "controls (hi-hat pedal, cymbal chokes, strike position), in time order",
    "POSE": "poses of one synth: a pose header, then rows of the dtype its READY announced",
    "HEARTBEAT": "the sender is alive (lets a gap at the end of a stream show)",
    "GAP": "the sender itself shed or lost events (queue full, source lost, upstream gap)",
    "SHOWN_ONSET": "an onset forwarded by the synth on its pose stream, `time_s` its show time "
    "(onset + D), for a display to sound and draw on time",
    "SHOWN_CONTROL": "a control forwarded likewise (grabs, hi-hat pedal), `time_s` its show "
    "time, so a display's sound cuts a ringing cymbal or hi-hat with the picture",
    "STAGE_CUE": "a cue's camera and blackout, sent by the synth when the beat tracker reaches "
    "the cue's bar, for every display to apply at that show time",
}

#: The header's fields in :data:`~livedrummer.protocol.spec.HEADER`'s order, with their meaning.
HEADER_FIELDS: tuple[tuple[str, str], ...] = (
    ("magic", "`LDRM`"),
    ("version", "the protocol version; any other is refused"),
    ("kind", "the message kind (below)"),
    ("flags", "flag bits (below); unknown bits are refused"),
    ("performer", "who played it (the same space as an onset's `source` field)"),
    ("stream", "the sender's stream id (below)"),
    (
        "seq",
        "+1 for every message on (performer, stream), heartbeats and gaps included; "
        "0 after a sender restart (see [Receiving a stream](../receiver.md))",
    ),
    ("send_time_s", "send time on the shared monotonic clock, seconds"),
    ("payload_len", "total bytes of the payload frames (checked against them)"),
)

_STRUCT_TYPES = {
    "s": "bytes",
    "B": "u8",
    "b": "i8",
    "H": "u16",
    "h": "i16",
    "I": "u32",
    "i": "i32",
    "Q": "u64",
    "q": "i64",
    "d": "f64",
    "f": "f32",
}


def _cell(text: str) -> str:
    """Text safe inside a Markdown table cell."""
    return " ".join(text.split()).replace("|", "\\|").replace("<", "&lt;")


def _struct_fields(fmt: str) -> list[tuple[int, int, str]]:
    """(offset, size, type) of each field of a little-endian ``struct`` format (``x`` pads)."""
    out: list[tuple[int, int, str]] = []
    offset, count = 0, ""
    for ch in fmt.lstrip("<>=!@"):
        if ch.isdigit():
            count += ch
            continue
        n, count = int(count or "1"), ""
        if ch == "x":
            offset += n
        elif ch == "s":
            out.append((offset, n, f"{n}s"))
            offset += n
        else:
            size = struct.calcsize("<" + ch)
            for _ in range(n):
                out.append((offset, size, _STRUCT_TYPES[ch]))
                offset += size
    return out


def _dtype_type(dt: np.dtype[Any]) -> str:
    return f"{dt.kind}{dt.itemsize * 8}"


def _dtype_table(dt: np.dtype[Any]) -> list[str]:
    assert dt.fields is not None  # a record dtype: the spec's rows are all records
    lines = ["| field | offset | type |", "|---|---|---|"]
    for name, (field, offset, *_) in dt.fields.items():
        lines.append(f"| `{name}` | {offset} | {_dtype_type(field)} |")
    return lines


_STRUCT_CODES = {"f8": "d", "f4": "f", "u1": "B", "i1": "b", "u2": "H", "u4": "I", "u8": "Q"}


def _struct_format(dt: np.dtype[Any]) -> str:
    """The little-endian ``struct`` format of a packed record dtype, checked against its size."""
    assert dt.fields is not None
    fmt = "<" + "".join(_STRUCT_CODES[f"{f.kind}{f.itemsize}"] for f, *_ in dt.fields.values())
    if struct.calcsize(fmt) != dt.itemsize:
        raise ValueError(f"{dt} is not packed: {fmt} is {struct.calcsize(fmt)} bytes")
    return fmt


def _hex(frame: bytes) -> str:
    return " ".join(frame[i : i + 1].hex() for i in range(len(frame)))


def _wire_example() -> list[str]:
    """One ONSET message encoded by the codec, byte for byte, and decoded back (checked)."""
    from livedrummer.kit.vocabulary import HiHat, Zone
    from livedrummer.protocol import Kind, Message, decode, encode, spec
    from livedrummer.timeline.events import ONSET_DTYPE, Onset, onsets_array

    hit = Onset(12.5, 38, 100, 9, "snare", Zone.HEAD, HiHat.NONE, 0.0, 0)
    msg = Message(Kind.ONSET, onsets_array([hit]), performer=0, seq=7, send_time_s=12.5004)
    frames = encode(msg)
    back = decode(frames)
    if back.seq != 7 or back.rows.tobytes() != msg.rows.tobytes():
        raise ValueError("the wire example does not decode to what was encoded")
    snippet = (
        "import struct\n\n"
        f'HEADER = struct.Struct("{spec.HEADER.format}")\n'
        f'ONSET = struct.Struct("{_struct_format(ONSET_DTYPE)}")\n'
        "magic, version, kind, flags, performer, stream, seq, send_time_s, payload_len = (\n"
        "    HEADER.unpack(frames[0])\n"
        ")\n"
        "for row in ONSET.iter_unpack(frames[1]):\n"
        "    time_s, note, velocity, channel, instrument, zone, hihat, openness, source = row\n"
    )
    scope: dict[str, Any] = {"frames": frames}
    exec(snippet, scope)  # the page's example, run: it must read what the codec wrote
    if (scope["kind"], scope["seq"], scope["note"], scope["time_s"]) != (
        int(Kind.ONSET),
        7,
        38,
        12.5,
    ):
        raise ValueError("the wire example's struct snippet does not read the frames")
    return [
        "## An example, byte for byte",
        "",
        "A snare head struck at velocity 100 on MIDI channel 10 (0-based 9) at 12.5 s on the "
        "shared clock, sent 0.4 ms later as message 7 of performer 0's event stream, as "
        "`livedrummer.protocol.encode` writes it (the build decodes it back):",
        "",
        "```text",
        f"frame 0, header ({len(frames[0])} bytes):",
        _hex(frames[0]),
        f"frame 1, one onset row ({len(frames[1])} bytes):",
        _hex(frames[1]),
        "```",
        "",
        "Read with Python's `struct` and the layouts above (the build runs this on the frames):",
        "",
        "```python",
        snippet.rstrip(),
        "```",
    ]


def wire_markdown() -> str:
    """The wire-protocol reference, from :mod:`livedrummer.protocol.spec`."""
    from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES
    from livedrummer.protocol import spec
    from livedrummer.timeline.events import ControlKind

    header = _struct_fields(spec.HEADER.format)
    if len(header) != len(HEADER_FIELDS):
        raise ValueError(
            f"docs_hooks.HEADER_FIELDS names {len(HEADER_FIELDS)} fields, "
            f"spec.HEADER has {len(header)}: update the table"
        )
    missing = [k.name for k in spec.Kind if k.name not in KIND_MEANING]
    if missing:
        raise ValueError(f"docs_hooks.KIND_MEANING lacks kinds {missing}: describe them")
    out = [
        "# Wire protocol",
        "",
        "<!-- Generated by deploy/docs_hooks.py from livedrummer/protocol/spec.py at every "
        "build: edit the code, not this page. -->",
        "",
        f"Protocol version **{spec.PROTOCOL_VERSION}**. Every message is a ZeroMQ multipart "
        f"message: one {spec.HEADER.size}-byte header frame (little-endian), then its payload "
        "frames. The payloads are the library's own numpy record arrays, sent as raw bytes; "
        "the one JSON payload (HELLO/READY) is parsed and checked key by key. Nothing is "
        "unpickled or evaluated. The table in `livedrummer/protocol/spec.py` drives encoding, "
        "decoding and this page.",
        "",
        "## Header frame",
        "",
        "| field | offset | size | type | meaning |",
        "|---|---|---|---|---|",
    ]
    for (name, meaning), (offset, size, kind) in zip(HEADER_FIELDS, header, strict=True):
        if name == "version":
            meaning = f"{spec.PROTOCOL_VERSION}: {meaning}"
        out.append(f"| {name} | {offset} | {size} | {kind} | {_cell(meaning)} |")
    out += [
        "",
        "Because the header starts with magic, version and kind, a SUB socket can subscribe to "
        "one kind by prefix (`MAGIC + version + kind`) without a topic frame.",
        "",
        "## Kinds",
        "",
        "| code | kind | payload frames | payload | what it is |",
        "|---|---|---|---|---|",
    ]
    for code, ks in sorted(spec.SPECS.items()):
        if ks.rows is not None:
            payload = f"n ≥ 1 rows of {ks.rows.itemsize} bytes (below)"
        elif ks.layout == "pose":
            assert ks.fixed is not None
            payload = f"pose header ({ks.fixed.size} bytes) + n ≥ 1 pose rows"
        elif ks.layout == "struct":
            assert ks.fixed is not None
            payload = f"a fixed {ks.fixed.size}-byte struct (below)"
        elif ks.layout == "json":
            payload = "UTF-8 JSON object (HELLO keys below)"
        else:
            payload = "empty (0 bytes)"
        out.append(
            f"| {code} | {ks.kind.name} | {ks.frames} | {_cell(payload)} | "
            f"{_cell(KIND_MEANING[ks.kind.name])} |"
        )
    out += ["", "## Payload rows", ""]
    by_rows: dict[str, tuple[np.dtype[Any], list[str]]] = {}
    for ks in spec.SPECS.values():
        if ks.rows is not None:
            by_rows.setdefault(repr(ks.rows.descr), (ks.rows, []))[1].append(ks.kind.name)
    for dt, kinds in by_rows.values():
        out += [f"### {', '.join(kinds)} ({dt.itemsize} bytes a row)", ""]
        out += _dtype_table(dt)
        out.append("")
    pose = spec.SPECS[spec.Kind.POSE].fixed
    gap = spec.SPECS[spec.Kind.GAP].fixed
    assert pose is not None and gap is not None
    out += [
        f"### POSE header ({pose.size} bytes)",
        "",
        "| field | offset | type |",
        "|---|---|---|",
    ]
    for (offset, _size, kind), name in zip(
        _struct_fields(pose.format), ("dtype hash", "rows", "time_s"), strict=True
    ):
        out.append(f"| {name} | {offset} | {kind} |")
    out += [
        "",
        "The pose rows' dtype belongs to the body engine: the synth announces it in READY as a "
        "canonical JSON description (`PoseFormat`) with an 8-byte BLAKE2b hash, and each POSE "
        "header repeats the hash, so a display built for another dtype refuses the frame.",
        "",
        f"### GAP payload ({gap.size} bytes)",
        "",
        "| field | offset | type |",
        "|---|---|---|",
    ]
    for (offset, _size, kind), name in zip(
        _struct_fields(gap.format),
        ("dropped", "first_time_s", "last_time_s", "reason"),
        strict=True,
    ):
        out.append(f"| {name} | {offset} | {kind} |")
    out += ["", "## Codes", ""]
    out += ["| header flag bit | name |", "|---|---|"]
    out += [f"| {int(f)} | {f.name} |" for f in spec.Flag]
    out += ["", "| stream id | name |", "|---|---|"]
    out += [f"| {int(s)} | {s.name} |" for s in spec.Stream]
    out += ["", "| GAP reason | name |", "|---|---|"]
    out += [f"| {int(r)} | {r.name} |" for r in spec.GapReason]
    out += ["", "| control `kind` | name |", "|---|---|"]
    out += [f"| {int(k)} | {k.name} |" for k in ControlKind]
    out += [
        "",
        "An onset's `instrument`, `zone` and `hihat` index these lists:",
        "",
        "| code | instrument | zone | hi-hat |",
        "|---|---|---|---|",
    ]
    for i in range(max(len(INSTRUMENTS), len(ZONES), len(HIHATS))):
        ins = INSTRUMENTS[i] if i < len(INSTRUMENTS) else ""
        zone = ZONES[i].value if i < len(ZONES) else ""
        hihat = HIHATS[i].value if i < len(HIHATS) else ""
        out.append(f"| {i} | {ins} | {zone} | {hihat} |")
    out += ["", *_wire_example()]
    out += [
        "",
        "## HELLO and READY",
        "",
        "One JSON object; these keys and no others (an optional key may be absent: a peer from "
        "before it was added).",
        "",
        "| key | required | what it holds |",
        "|---|---|---|",
    ]
    for name, (required, what) in spec.HELLO_KEYS.items():
        out.append(f"| `{name}` | {'yes' if required else 'no'} | {_cell(what)} |")
    out += [
        "",
        "## Limits a receiver checks",
        "",
        f"- payload at most {spec.MAX_PAYLOAD // (1024 * 1024)} MiB, equal to the frames' total;",
        f"- row payloads a whole number of rows, 1 to {spec.MAX_ROWS:,} rows;",
        f"- HELLO/READY JSON at most {spec.MAX_HELLO // 1024} KiB;",
        f"- a pose row at most {spec.MAX_POSE_ITEMSIZE // (1024 * 1024)} MiB;",
        "- every onset and control field in range (codes index the lists above, MIDI values "
        "below 128, channels below 16, times finite).",
        "",
        "A message that breaks any of these is dropped and counted by kind, with one log line "
        "per kind; the receiver keeps serving. Kinds a peer does not know are refused the same "
        "way, never misread. How subscribers treat sequence numbers: "
        "[Receiving a stream](../receiver.md).",
        "",
    ]
    return "\n".join(out)


def _subparsers(parser: argparse.ArgumentParser) -> list[tuple[str, str, argparse.ArgumentParser]]:
    """(name, one-line help, parser) of each subcommand ``--help`` lists, in its order."""
    found: list[tuple[str, str, argparse.ArgumentParser]] = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                found.append((choice.dest, choice.help or "", action.choices[choice.dest]))
    return found


class _Captured(Exception):  # noqa: N818 (not an error: it carries a parser out of main)
    def __init__(self, parser: argparse.ArgumentParser) -> None:
        super().__init__(parser.prog)
        self.parser = parser


_PROBE = "--livedrummer-docs-probe"


def _bench_parsers() -> list[tuple[str, str, argparse.ArgumentParser]]:
    """Each benchmark's parser. A benchmark builds it inside ``main(argv)`` and parses first
    thing; ``parse_args`` is intercepted for a probe argument, so the parser comes back and
    nothing is measured. A benchmark that returned instead would have run: that stops the build.
    """
    import importlib

    from services.cli.bench import available

    found = []
    original = argparse.ArgumentParser.parse_args

    def probe(self: argparse.ArgumentParser, args: Any = None, namespace: Any = None) -> Any:
        if args == [_PROBE]:
            raise _Captured(self)
        return original(self, args, namespace)

    argparse.ArgumentParser.parse_args = probe  # type: ignore[method-assign]
    try:
        for name in available():
            module = importlib.import_module(f"services.bench.{name}")
            try:
                module.main([_PROBE])
            except _Captured as got:
                found.append((name, "", got.parser))
            else:
                raise ValueError(f"services/bench/{name}.py: main() did not parse its argv first")
    finally:
        argparse.ArgumentParser.parse_args = original  # type: ignore[method-assign]
    return found


def _parser_markdown(path: str, summary: str, parser: argparse.ArgumentParser) -> list[str]:
    depth = min(path.count(" ") + 1, 5)
    out = [f"{'#' * (depth + 1)} {path}", ""]
    text = (parser.description or summary).strip().split("\n\n")[0]
    if text:
        out += [_cell(_inline(text)), ""]
    usage = parser.format_usage().strip()
    out += ["```text", usage.removeprefix("usage: "), "```", ""]
    formatter = parser._get_formatter()
    rows = []
    for action in parser._actions:
        if action.help == argparse.SUPPRESS or isinstance(action, argparse._SubParsersAction):
            continue
        if isinstance(action, argparse._HelpAction):
            continue
        invocation = formatter._format_action_invocation(action)
        helptext = formatter._expand_help(action) if action.help else ""
        rows.append(f"| `{invocation}` | {_cell(helptext)} |")
    if rows:
        out += ["| argument | what it does |", "|---|---|", *rows, ""]
    subs = _subparsers(parser)
    if path == "livedrummer bench":
        subs = _bench_parsers()
    for name, sub_summary, sub in subs:
        out += _parser_markdown(f"{path} {name}", sub_summary, sub)
    return out


def cli_markdown() -> str:
    """The CLI reference: every subcommand and option of ``livedrummer``, from its parsers."""
    from services.cli import build_parser

    columns = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # usage lines wrapped the same on every machine
    try:
        return _cli_page(build_parser(None))
    finally:
        if columns is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = columns


def _cli_page(parser: argparse.ArgumentParser) -> str:
    out = [
        "# Command-line reference",
        "",
        "<!-- Generated by deploy/docs_hooks.py from the argparse parsers of services/cli at "
        "every build: edit the code, not this page. -->",
        "",
        "Every subcommand of `livedrummer` and every option, as `livedrummer COMMAND --help` "
        "prints them. Each option's help states its default. Former spellings of options "
        "still work, with a warning, and are not listed.",
        "",
        "| command | what it does |",
        "|---|---|",
    ]
    subs = _subparsers(parser)
    out += [f"| [`{name}`](#livedrummer-{name}) | {_cell(summary)} |" for name, summary, _ in subs]
    out.append("")
    top = _parser_markdown("livedrummer", "", parser)
    # The top parser's own section, then each subcommand at the next level.
    out += top
    return "\n".join(out)


#: The file-format references, each from the docstrings that define the format:
#: page -> (title, what it covers, modules whose docstrings are its sections).
FORMAT_PAGES: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "reference/kit-files.md": (
        "Kit, extension and note-map files",
        "Kits (`kits/*.toml`), kit extensions (`kits/extensions/*.toml`) and note maps "
        "(`kits/maps/*.toml`). Your own go in `~/.config/livedrummer/kits/` (and `maps/`, "
        "`extensions/` below it) or any folder of `$LIVEDRUMMER_PATH`, or pass a `.toml` path "
        "to `--kit` / `--map`. The bundled ones: [Kits and note maps](../guide/kits-and-maps.md).",
        ("livedrummer.kit.loader", "livedrummer.midi.notemap"),
    ),
    "reference/stage-file.md": (
        "Stage files",
        "A stage file names the performers of `render --stage`, `check --stage` and "
        "`up --stage`, places them and makes ensembles. How to use one: "
        "[Several drummers on one stage](../guide/stage.md).",
        (
            "livedrummer.stage.stagefile",
            "livedrummer.stage.source",
            "livedrummer.stage.formation",
            "livedrummer.stage.variation",
        ),
    ),
    "reference/presets.md": (
        "Expression presets and live parameters",
        "Presets (`kits/presets/*.toml`, `--preset NAME` or a path) and the live parameters "
        "of `/livedrummer/param/NAME` share one table.",
        ("livedrummer.body.expression",),
    ),
    "reference/show-files.md": (
        "Rig profile, cue lists and controller maps",
        "The files a show reads: the rig profile (`rig.toml`, `up`'s defaults), cue lists "
        "(`--cues FILE`) and controller maps (`up --control FILE`). How to use them: "
        "[Run the show live](../guide/show-control.md) and [The rig](../guide/rig.md).",
        ("livedrummer.live.profile", "livedrummer.live.cues", "livedrummer.live.controlmap"),
    ),
}

_ROLE = re.compile(r":[a-z]+:`~?([^`<]*?)(?: <[^>]*>)?`")


def _inline(text: str) -> str:
    """reStructuredText inline markup as Markdown: ````x```` and ``:func:`a.b```."""

    def role(match: re.Match[str]) -> str:
        target = match.group(1)
        return f"`{target.rsplit('.', 1)[-1]}`" if "~" in match.group(0) else f"`{target}`"

    return _ROLE.sub(role, text.replace("``", "`"))


def docstring_markdown(module: str) -> str:
    """A module docstring as a Markdown section: its first line the heading, ``::`` blocks
    fenced, roles and double backquotes as code; a "Why this shape" paragraph (the design,
    for developers) is left out."""
    path = Path(__file__).resolve().parent.parent / (module.replace(".", "/") + ".py")
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))
    if not doc:
        raise ValueError(f"{path}: no module docstring to document its format from")
    first, _, rest = doc.partition("\n")
    out = [f"## {_inline(first.strip().rstrip('.'))}", "", f"*From `{module}`.*", ""]
    paragraphs = re.split(r"\n\s*\n", rest.strip("\n"))
    block: list[str] = []  # the indented paragraphs of a literal block, after a "::"
    literal = False
    for para in [*paragraphs, ""]:
        if literal and para.startswith((" ", "\t")):
            block.append(textwrap.dedent(para).replace("``", "`"))
            continue
        if block:
            code = "\n\n".join(block)
            lang = "toml" if re.search(r"^(\[|\w+ = )", code, re.M) else "text"
            out += [f"```{lang}", code, "```", ""]
            block = []
        literal = False
        if not para or para.startswith("Why this shape"):
            continue
        text = _inline(para)
        # A list needs a blank line before it in Markdown; in a docstring it follows its lead-in.
        text = re.sub(r"(?m)^([^*\s-].*)\n(\* )", r"\1\n\n\2", text)
        if text.endswith("::"):
            literal = True
            text = text[:-2].rstrip() + ":"
        out += [text, ""]
    return "\n".join(out)


def format_markdown(page: str) -> str:
    """One file-format reference page of :data:`FORMAT_PAGES`."""
    title, intro, modules = FORMAT_PAGES[page]
    out = [
        f"# {title}",
        "",
        "<!-- Generated by deploy/docs_hooks.py from the docstrings of the modules that read "
        "these files, at every build: edit the code, not this page. -->",
        "",
        intro,
        "",
    ]
    for module in modules:
        out.append(docstring_markdown(module))
    if page == "reference/presets.md":
        from livedrummer.body.expression import params_markdown

        out += ["## Parameters", "", params_markdown(), ""]
    return "\n".join(out)


def generated_pages() -> dict[str, str]:
    """Every generated page: its path under ``docs/`` and its Markdown."""
    pages = {"reference/cli.md": cli_markdown(), "reference/wire.md": wire_markdown()}
    pages.update({page: format_markdown(page) for page in FORMAT_PAGES})
    return pages


def on_files(files: Any, config: Any) -> Any:
    """MkDocs event: add the generated pages to the build's files."""
    from mkdocs.structure.files import File

    for uri, content in generated_pages().items():
        files.append(File.generated(config, uri, content=content))
    return files
