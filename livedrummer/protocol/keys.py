"""CURVE key files: a tiny text format, parsed strictly, shared with pyzmq's authenticator.

Why this format. A remote jam authenticates peers with ZeroMQ CURVE key pairs. pyzmq's ZAP
authenticator (``configure_curve(location=DIR)``) reads every ``*.key`` file in a folder
with its own line reader, so our public key files must be readable by it; we therefore
write the same small subset of ZeroMQ's certificate text, and nothing else::

    # livedrummer CURVE public key "alice"
    curve
        public-key = "<40 Z85 characters>"

The secret file (``NAME.key_secret``, mode 0600) has the same shape plus a ``secret-key``
line. Our parser accepts exactly that: comments (``#``), blank lines, the section words
``metadata`` and ``curve``, and ``public-key`` / ``secret-key`` assignments with a quoted
40-character Z85 value. Anything else is a :class:`~livedrummer.errors.KeyFileError`
naming the file and line. Nothing here evaluates or unpickles anything.

Limits: the parser does not check that a secret key matches its public key (that needs
libzmq's ``curve_public``; :mod:`services.wire.net` does it when loading a secret); metadata
entries are ignored, not kept.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from livedrummer.errors import KeyFileError

PUBLIC_SUFFIX = ".key"
SECRET_SUFFIX = ".key_secret"
Z85_ALPHABET = (
    "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ.-:+=^!/*?&<>()[]{}@%$#"
)
KEY_LENGTH = 40  # a 32-byte CURVE key in Z85
MAX_FILE_BYTES = 4096
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
_ASSIGN = re.compile(r"^(public-key|secret-key)\s*=\s*\"([^\"]*)\"$")


@dataclass(frozen=True)
class KeyPair:
    """Z85 text of a CURVE public key and, for a ``.key_secret`` file, its secret key."""

    public: bytes
    secret: bytes | None = None


def check_name(name: str) -> str:
    """Return ``name`` if it can name a key file (letters, digits, ``_ . -``), else raise."""
    if not _NAME.match(name):
        raise KeyFileError(
            f"key name {name!r}: use 1-64 letters, digits, '_', '.' or '-' (no path separators)"
        )
    return name


def check_key(value: str, where: str, field: str) -> bytes:
    """Return a Z85 key as bytes, or raise naming ``where`` and ``field``."""
    if len(value) != KEY_LENGTH or any(c not in Z85_ALPHABET for c in value):
        raise KeyFileError(f"{where}: {field} is not a {KEY_LENGTH}-character Z85 key")
    return value.encode("ascii")


def format_key_file(name: str, public: bytes, secret: bytes | None = None) -> str:
    """The text of a public (``secret`` None) or secret key file; see the module docstring."""
    check_name(name)
    pub = check_key(public.decode("ascii", "replace"), f"key {name!r}", "public-key")
    what = "secret key pair" if secret is not None else "public key"
    lines = [
        f'# livedrummer CURVE {what} "{name}"',
        "# Z85 text; read by livedrummer and by pyzmq's authenticator.",
    ]
    if secret is not None:
        lines.append("# Keep this file private (mode 0600); share only the .key file.")
    lines += ["curve", f'    public-key = "{pub.decode()}"']
    if secret is not None:
        sec = check_key(secret.decode("ascii", "replace"), f"key {name!r}", "secret-key")
        lines.append(f'    secret-key = "{sec.decode()}"')
    return "\n".join(lines) + "\n"


def parse_key_file(text: str, where: str) -> KeyPair:
    """Parse the text of a key file; ``where`` (usually the path) names it in errors."""
    keys: dict[str, bytes] = {}
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#") or line in ("curve", "metadata"):
            continue
        m = _ASSIGN.match(line)
        if m is None:
            raise KeyFileError(f"{where}:{number}: unexpected line {line[:40]!r}")
        field, value = m.group(1), m.group(2)
        if field in keys:
            raise KeyFileError(f"{where}:{number}: {field} given twice")
        keys[field] = check_key(value, f"{where}:{number}", field)
    if "public-key" not in keys:
        raise KeyFileError(f"{where}: no public-key line")
    return KeyPair(keys["public-key"], keys.get("secret-key"))


def read_key_file(path: Path, *, secret: bool) -> KeyPair:
    """Read a key file; with ``secret`` it must hold a secret key too."""
    try:
        data = path.read_bytes()[: MAX_FILE_BYTES + 1]
    except OSError as exc:
        raise KeyFileError(f"{path}: cannot read key file: {exc.strerror or exc}") from None
    if len(data) > MAX_FILE_BYTES:
        raise KeyFileError(f"{path}: too large for a key file (> {MAX_FILE_BYTES} bytes)")
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        raise KeyFileError(f"{path}: not a key file (non-ASCII bytes)") from None
    pair = parse_key_file(text, str(path))
    if secret and pair.secret is None:
        raise KeyFileError(
            f"{path}: no secret-key line (give the {SECRET_SUFFIX} file, not the public one)"
        )
    return pair
