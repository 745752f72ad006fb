"""Which MIDI channels of a file are its drums.

General MIDI puts the drum kit on channel 10 (9 counted from 0), and a full-band song holds
piano, bass and guitar notes on the other channels: looked up in a drum note map, a bass line
becomes kicks and toms. So a file's drums are chosen before any note is decoded, from counts
the file reader gathers in its first pass (note-ons per channel, program changes, bank
selects), by :func:`choose_drum_channels`:

* ``"all"`` reads every channel; an ``int`` (0-based) reads that channel only;
* ``"auto"`` (the default) reads the *drum channels* when notes are on more than one channel.
  A drum channel is channel 10, or one that selects a rhythm bank (bank select MSB 120, as
  General MIDI 2 does, or 127, as XG does). A file whose notes are all on one other channel is
  read as drums only when nothing says it is melodic (a program change to an instrument that
  is not one of General MIDI's percussive programs 113-120); otherwise it has no drum part.

Every choice that leaves notes out, or reads a channel that is not channel 10, says so in one
line (:attr:`DrumChannels.notice`); the notes left out are counted per channel by the decoder.
Channels are 0-based inside the library and 1-based in every message a person reads.

Limits: a Roland GS file can turn another part into a drum part by SysEx; that message is not
read, so such a part counts as melodic (``--channel N`` reads it).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Literal

GM_DRUM_CHANNEL = 9  # channel 10, counted from 0
#: Bank select (CC0) values that choose a rhythm (drum) bank: GM2 (0x78) and XG (0x7F).
DRUM_BANKS = frozenset({120, 127})
#: General MIDI programs (0-based) that are percussive sounds, not melodic instruments:
#: Tinkle Bell, Agogo, Steel Drums, Woodblock, Taiko Drum, Melodic Tom, Synth Drum, Reverse Cymbal.
PERCUSSIVE_PROGRAMS = range(112, 120)

ChannelChoice = int | Literal["auto", "all"]


@dataclass(frozen=True, slots=True)
class DrumChannels:
    """The channels read as drums (``None``: all) and the line that explains the choice."""

    channels: frozenset[int] | None
    notice: str = ""
    no_drum_part: bool = False


def parse_channel(text: str) -> ChannelChoice:
    """``--channel``'s value: ``auto``, ``all`` or a channel 1-16 (returned 0-based)."""
    word = text.strip().lower()
    if word in ("auto", "all"):
        return "auto" if word == "auto" else "all"
    if word.isdigit() and 1 <= int(word) <= 16:
        return int(word) - 1
    raise ValueError(f"expected auto, all or a channel 1-16 (got {text!r})")


def channel_list(channels: Iterable[int]) -> str:
    """0-based channels as a person reads them: ``1-9, 11``."""
    numbers = sorted(c + 1 for c in channels)
    runs: list[list[int]] = []
    for n in numbers:
        if runs and n == runs[-1][-1] + 1:
            runs[-1].append(n)
        else:
            runs.append([n])
    return ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 2 else ", ".join(map(str, r)) for r in runs)


def choose_drum_channels(
    choice: ChannelChoice,
    notes: Mapping[int, int],
    programs: Mapping[int, Iterable[int]],
    drum_banks: Iterable[int] = (),
) -> DrumChannels:
    """The drum channels of a file (see the module docstring).

    ``notes``: note-ons per 0-based channel; ``programs``: the programs each channel selects;
    ``drum_banks``: channels that select a rhythm bank.
    """
    used = {c for c, n in notes.items() if n > 0}
    if choice == "all":
        return DrumChannels(None)
    if not isinstance(choice, str):
        left = {c: n for c, n in notes.items() if c != choice and n > 0}
        notice = ""
        if left:
            notice = (
                f"{_count(sum(left.values()))} on {_channels(left)} ignored "
                f"(--channel {choice + 1}; --channel all reads them)"
            )
        return DrumChannels(frozenset({choice}), notice, no_drum_part=notes.get(choice, 0) == 0)
    if not used:
        return DrumChannels(None)
    drums = {c for c in used if c == GM_DRUM_CHANNEL or c in set(drum_banks)}
    if len(used) == 1 and not drums:
        (only,) = used
        melodic = sorted(p + 1 for p in programs.get(only, ()) if p not in PERCUSSIVE_PROGRAMS)
        total = _count(notes[only])
        if melodic:
            return DrumChannels(
                frozenset(),
                f"no drum part: all {total} are on channel {only + 1}, which plays melodic "
                f"program {melodic[0]} (--channel {only + 1} reads it as drums)",
                no_drum_part=True,
            )
        return DrumChannels(
            frozenset({only}),
            f"all {total} are on channel {only + 1}, not the drum channel 10: read as drums "
            "(no melodic program on it)",
        )
    if not drums:
        left = {c: notes[c] for c in used}
        return DrumChannels(
            frozenset(),
            f"no drum part: {_count(sum(left.values()))} on {_channels(left)}, none on the drum "
            "channel 10 (--channel N reads channel N as drums)",
            no_drum_part=True,
        )
    left = {c: notes[c] for c in used - drums}
    if not left:
        return DrumChannels(frozenset(drums))
    return DrumChannels(
        frozenset(drums),
        f"{_count(sum(left.values()))} on {_channels(left)} ignored; --channel all to use them",
    )


def _count(n: int) -> str:
    return f"{n:,} note" + ("" if n == 1 else "s")


def _channels(channels: Mapping[int, int]) -> str:
    return ("channel " if len(channels) == 1 else "channels ") + channel_list(channels)
