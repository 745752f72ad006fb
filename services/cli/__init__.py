"""The ``livedrummer`` command: one entry point, one module per subcommand.

The CLI is an I/O edge: it parses arguments, calls the library, prints, and turns every
:class:`~livedrummer.errors.LivedrummerError` into one line on stderr and exit status 2 (no
traceback: a show technician needs the file and the problem, not a stack). Each subcommand is a
module in this package with ``register(subparsers)``. Start-up is lazy, so that ``livedrummer
--help`` and ``livedrummer kits`` answer at once (no numpy, no sockets, no GPU): :data:`COMMANDS`
holds every subcommand's one-line help, ``--help`` is built from it alone, and a command line
imports only the module of the subcommand it names; that module's heavy imports (numpy, audio,
GPU, sockets) happen inside its command function. Adding a subcommand is adding a module and
its line to :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence

from livedrummer import __version__
from livedrummer.errors import LivedrummerError

EXIT_USAGE = 2

#: Subcommand modules of this package and their one-line help, in the order ``--help`` lists
#: them (each module's parser takes its help from here).
COMMANDS: dict[str, str] = {
    "demo": "run the pipeline on the bundled demo groove and show it",
    "inspect": "summarize a MIDI file: tempo, meter, onsets per piece",
    "kits": "list kits, note maps, presets and avatars",
    "sticking": "which limb plays each note of a MIDI file",
    "bench": "run a benchmark and print its figures",
    "input": "capture a kit, trigger board, file or remote stream",
    "ports": "list MIDI input ports (for livedrummer input --midi)",
    "monitor": "print what a kit sends and what each message means",
    "map": "learn a note map for a new module by hitting its pads",
    "calibrate": "measure the kit's input offset by hitting along to a click",
    "practice": "play along with a reference, scored note by note",
    "control": "map a MIDI controller's faders and pads to show parameters, cameras and cues",
    "sessions": "list journaled live sessions or export one to MIDI",
    "check": "check contact, penetration and joint limits of the motion",
    "export": "export the drummer's motion as BVH",
    "render": "render a MIDI file to a video (MP4 with sound) or PNGs",
    "display": "play a MIDI file in a window with transport keys",
    "synth": "turn live onsets into drummer poses (online)",
    "up": "run the live pipeline: input, synth and display",
    "relay": "fan a synth's poses out to many displays (and to other relays)",
    "deploy": "write a systemd user unit that starts the rig at boot",
    "keys": "make and list CURVE key pairs for remote streams",
    "avatar": "describe an avatar file: bones, proportions, triangles, textures",
    "avatars": "list the avatars --avatar NAME can pick",
    "transcribe": "transcribe a drum recording (audio file) to a MIDI file",
    "audio": "learn an acoustic kit's sound (audio profile) for transcribe and input --audio",
    "acoustic": "train the acoustic drum recogniser's model on the drum kits installed here",
}


def command_named(argv: Sequence[str]) -> str | None:
    """The subcommand a command line names: its first word that is not an option."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; given ``argv``, only the subcommand it names is built (see above)."""
    from .common import Parser

    parser = Parser(
        prog="livedrummer",
        description="Turn an electronic drum kit or a MIDI file into a 3D virtual drummer.",
    )
    parser.add_argument("--version", action="version", version=f"livedrummer {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log more detail")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    wanted = None if argv is None else command_named(argv)
    for name, summary in COMMANDS.items():
        if argv is None or name == wanted:
            importlib.import_module(f".{name}", __package__).register(sub)
        elif wanted is None:  # the list for --help or for an error: no other module needed
            sub.add_parser(name, help=summary, description=summary)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    words = sys.argv[1:] if argv is None else list(argv)
    args = build_parser(words).parse_args(words)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.WARNING,
        format="livedrummer: %(levelname)s: %(message)s",
    )
    try:
        code: int = args.func(args)
    except LivedrummerError as exc:
        print(f"livedrummer: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
