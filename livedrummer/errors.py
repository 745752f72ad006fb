"""The exception hierarchy.

Every error a user can cause (a bad file, a typo in a kit, an unknown map name) is a
``LivedrummerError`` whose message names *where* (file, key, byte offset) and *what*. The CLI
prints ``str(error)`` on one line and exits with status 2; services log it and keep running.
Programming errors stay ordinary Python exceptions so they are never mistaken for bad input.
"""

from __future__ import annotations


class LivedrummerError(Exception):
    """Base of all errors caused by input, configuration or the environment."""


class ConfigError(LivedrummerError):
    """A TOML configuration file (kit, note map, preset) is malformed or inconsistent."""


class KitError(ConfigError):
    """A kit file is wrong, or a kit name is unknown."""


class NoteMapError(ConfigError):
    """A note-map file is wrong, or a map name is unknown."""


class MidiFileError(LivedrummerError):
    """A Standard MIDI File cannot be read."""


class MidiInputError(LivedrummerError):
    """A live MIDI or serial source failed."""


class ProtocolError(LivedrummerError):
    """A message on the wire (ZeroMQ frames) is malformed, of another version, or too large."""


class JournalError(LivedrummerError):
    """A session journal cannot be written or read."""


class PresetError(ConfigError):
    """An expression preset file is wrong, or a preset name is unknown."""


class UnreachableError(KitError):
    """A piece of a kit lies out of the drummer's reach (named with the limb and the gap)."""


class KeyFileError(LivedrummerError):
    """A CURVE key file is missing, malformed, or its two keys do not belong together."""
