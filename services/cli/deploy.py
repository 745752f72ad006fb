"""``livedrummer deploy systemd``: a user unit that starts this machine's rig at boot.

The unit runs ``up --rig FILE --wait`` with the interpreter and package this command runs
from (the installed CLI, a virtual environment or a checkout alike: no path is assumed), so
the show described by the rig profile (:mod:`livedrummer.live.profile`) starts when the user's
session does and waits for the kit to be switched on. ``up`` supervises input, synth and
display and restarts whichever dies; systemd restarts ``up`` itself on a failure, except on
exit status 2, a configuration error (a typo in rig.toml, a camera that does not exist), which
no restart would fix (``RestartPreventExitStatus=2``). With ``--print`` the unit goes to
stdout; otherwise it is written to ``~/.config/systemd/user/`` (``--unit-dir``) and the two
commands that enable it are printed.

Limits: a window on a projector needs the graphical session's environment in the user
manager (``systemctl --user import-environment DISPLAY WAYLAND_DISPLAY XAUTHORITY``, which
the printed commands include); the unit is a user unit, so the rig runs as that user.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from .parsing import Subparsers, add_command

UNIT_NAME = "livedrummer-rig.service"


def register(sub: Subparsers) -> None:
    p = add_command(sub, "deploy", run, "write a systemd user unit that starts the rig at boot")
    what = p.add_subparsers(dest="target", required=True, metavar="TARGET")
    sd = what.add_parser(
        "systemd",
        help="a user unit running `up --rig FILE --wait`",
        description="A user unit running `up --rig FILE --wait`.",
    )
    sd.add_argument("--print", action="store_true", help="print the unit instead of writing it")
    sd.add_argument(
        "--unit-dir",
        type=Path,
        metavar="DIR",
        help="where to write it (default ~/.config/systemd/user)",
    )
    sd.add_argument(
        "--rig",
        type=Path,
        metavar="FILE",
        help="rig profile to run (default $LIVEDRUMMER_HOME/rig.toml)",
    )


def unit_text(rig: Path, argv: list[str]) -> str:
    """The unit for ``argv`` (the command that runs livedrummer) and the profile ``rig``."""
    command = " ".join(shlex.quote(a) for a in [*argv, "up", "--rig", str(rig), "--wait"])
    return (
        "# Written by `livedrummer deploy systemd`: the rig described by the profile below.\n"
        "[Unit]\n"
        "Description=livedrummer rig (input, synth and display from rig.toml)\n"
        "After=sound.target graphical-session.target\n"
        "\n"
        "[Service]\n"
        "Type=simple\n"
        f"ExecStart={command}\n"
        "Environment=PYTHONUNBUFFERED=1\n"
        "Restart=on-failure\n"
        "RestartSec=2\n"
        "# exit status 2 is a configuration error: restarting would not fix it\n"
        "RestartPreventExitStatus=2\n"
        "LimitRTPRIO=40\n"
        "\n"
        "[Install]\n"
        "WantedBy=default.target\n"
    )


def run(args: argparse.Namespace) -> int:
    from livedrummer.errors import ConfigError
    from livedrummer.live.profile import RigProfile, default_path

    from ..process.program import program_argv

    rig = (args.rig or default_path()).expanduser().resolve()
    if rig.exists():
        RigProfile.load(rig)  # a broken profile is one line now, not a unit failing at boot
    else:
        print(
            f"deploy: note: {rig} does not exist yet; write it before starting the unit "
            "(see 'Run the rig at boot' in docs/guide/rig.md)",
            file=sys.stderr,
        )
    text = unit_text(rig, program_argv())
    if args.print:
        print(text, end="")
        return 0
    folder = args.unit_dir or Path.home() / ".config" / "systemd" / "user"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / UNIT_NAME).write_text(text)
    except OSError as exc:
        raise ConfigError(f"{folder / UNIT_NAME}: cannot write: {exc.strerror or exc}") from None
    print(f"wrote {folder / UNIT_NAME}; to start the rig at boot run:")
    print("  systemctl --user daemon-reload")
    print("  systemctl --user import-environment DISPLAY WAYLAND_DISPLAY XAUTHORITY")
    print(f"  systemctl --user enable --now {UNIT_NAME}")
    print("  loginctl enable-linger  # start it at boot, before anyone logs in")
    return 0
