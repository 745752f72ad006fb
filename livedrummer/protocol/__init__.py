"""The livedrummer wire format: versioned multipart ZeroMQ messages, one table drives it all.

Why this shape. Onsets, controls and poses are already fixed-dtype numpy record arrays inside
the library, so the cheapest safe wire format is *those bytes*: a small fixed-layout header
frame followed by raw payload frame(s). Nothing that crosses a socket is unpickled or
evaluated; the one JSON payload (HELLO/READY, sent once per connection) is parsed with
``json.loads`` and checked key by key. :data:`SPECS` is the single table of message kinds:
:func:`encode` and :func:`decode` both read it, so the documented schema below *is* the code.

Header frame (:data:`HEADER`, little-endian, 32 bytes)::

    offset size field         type  meaning
    0      4    magic         4s    b"LDRM"
    4      1    version       u8    PROTOCOL_VERSION (2); any other value is refused
    5      1    kind          u8    Kind (table below)
    6      2    flags         u16   Flag bits; unknown bits are refused
    8      2    performer     u16   who played it (same space as the onset ``source`` field)
    10     2    stream        u16   sender's stream id (Stream); sequence numbers count per
                                    (performer, stream)
    12     8    seq           u64   sequence number, +1 for *every* message on the stream
                                    (heartbeats and gaps included), 0 after a sender restart
    20     8    send_time_s   f64   send time on the shared clock (livedrummer.timeline.clock)
    28     4    payload_len   u32   total bytes of the payload frames (checked)

Because the header starts with magic, version and kind, a SUB socket can filter one kind with
:func:`topic` (e.g. onsets only) without a separate topic frame.

Kinds (:data:`SPECS`; "frames" counts the payload frames after the header)::

    kind       code frames payload
    HELLO      1    1      UTF-8 JSON object (Hello), keys in spec.HELLO_KEYS: service,
                           role, protocol, performer, endpoints {name: zmq endpoint}, pose
                           (PoseFormat JSON or null), avatar (digest; may be absent)
    READY      2    1      same JSON as HELLO: the service's answer, sent once it is serving
    ONSET      3    1      n >= 1 rows of events.ONSET_DTYPE (20 bytes each), time order
    CONTROL    4    1      n >= 1 rows of events.CONTROL_DTYPE (14 bytes each), time order
    POSE       5    2      POSE_HEADER (hash 8s, rows u32, pad 4, time_s f64; 24 bytes)
                           + n >= 1 rows of the pose dtype announced in HELLO/READY
    HEARTBEAT  6    1      empty (0 bytes): the sender is alive; lets a tail gap show
    GAP        7    1      GAP_PAYLOAD (dropped u64, first_time_s f64, last_time_s f64,
                           reason u32; 28 bytes): the *sender* shed or lost events
    SHOWN_ONSET 8   1      n >= 1 rows of events.ONSET_DTYPE, ``time_s`` the onset's *show
                           time* (its time + the synth's D): the synth forwards each onset
                           on its pose stream as it arrives, so a display can sound it (and
                           draw a score) at the moment the picture shows its contact
                           (version 2; version 1 had no kind 8)
    SHOWN_CONTROL 9 1      n >= 1 rows of events.CONTROL_DTYPE, ``time_s`` the control's
                           show time: the synth forwards cymbal grabs and hi-hat pedal
                           moves as it forwards onsets, so a display's sound cuts a ringing
                           cymbal or hi-hat when the picture's does. Still version 2: a
                           peer that predates kind 9 refuses it as an unknown kind (counted
                           as a bad message, never misread)
    STAGE_CUE 10    1      n >= 1 rows of events.STAGE_CUE_DTYPE (15 bytes: time_s f64 show
                           time, bar u32, camera u8 0 or 1..8, cut u8 0/1, blackout i8
                           -1/0/1): a cue's camera and blackout, which the synth sends on
                           its pose stream when the beat tracker reaches the cue's bar, for
                           every display to apply at that show time (a version-2 peer from
                           before kind 10 refuses it as an unknown kind: counted, not misread)

Limits checked by :func:`decode`: header size exact; payload_len <= ``max_payload``
(default :data:`MAX_PAYLOAD`, 16 MiB) and equal to the frames' total; row payloads a whole
number of rows, 1 … :data:`MAX_ROWS`; every onset/control field in range (codes index the
vocabulary, MIDI values < 128, channels < 16, times finite); POSE rows match the announced
dtype's hash and size; HELLO JSON <= 64 KiB with the keys of ``HELLO_KEYS`` only, every
required one there. Any violation raises
:class:`~livedrummer.errors.ProtocolError` naming the field and the value, and nothing else is
ever raised on bad bytes (a hypothesis fuzz test holds us to it). Errors about the wire are
:class:`WireError`, whose ``field`` attribute names that field for a program (``"version"``,
``"payload_len"``, ``"row 3.note"``; ``"max_payload"`` for the size limit), so a receiver can
count its drops by kind without parsing the message.

The pose dtype belongs to the body engine and is opaque here: :class:`PoseFormat` turns any
structured dtype (scalar or nested fields, subarrays, padding; no Python objects) into a
canonical JSON description and an 8-byte BLAKE2b hash. The synth announces it in READY, and
each POSE header repeats the hash so a display built against another dtype refuses the frame.

Decoded arrays are zero-copy, read-only views of the received frames. Limits: no
compression, no fragmentation (one message <= ``max_payload``), integrity is ZeroMQ's (TCP),
and authentication/encryption are a socket option (CURVE), not part of this format.

Modules, one concept each: :mod:`~livedrummer.protocol.spec` (the table, constants and
:class:`WireError`), :mod:`~livedrummer.protocol.poseformat`, :mod:`~livedrummer.protocol.bodies`
(the message and its bodies), :mod:`~livedrummer.protocol.rows` (row checks),
:mod:`~livedrummer.protocol.codec` (encode/decode), :mod:`~livedrummer.protocol.sequence`
(the one policy for gaps, restarts and duplicates seen in sequence numbers) and
:mod:`~livedrummer.protocol.intake` (a subscriber's decode, filter and observe steps);
:mod:`~livedrummer.protocol.journal` is the same stream written to disk (the session journal).
Import from the package: its names are the wire's API.
"""

from __future__ import annotations

from livedrummer.errors import ProtocolError
from livedrummer.protocol.bodies import Body, Gap, Hello, Message, Pose
from livedrummer.protocol.codec import decode, encode
from livedrummer.protocol.intake import Dropped, StreamIntake, Taken, kind_of
from livedrummer.protocol.poseformat import PoseFormat
from livedrummer.protocol.rows import check_controls, check_onsets, check_stage_cues
from livedrummer.protocol.sequence import SeqReport, SeqStats, SeqStatus, SequenceTracker
from livedrummer.protocol.spec import (
    GAP_PAYLOAD,
    HEADER,
    HELLO_KEYS,
    KNOWN_FLAGS,
    MAGIC,
    MAX_HELLO,
    MAX_PAYLOAD,
    MAX_POSE_ITEMSIZE,
    MAX_ROWS,
    POSE_HEADER,
    PROTOCOL_VERSION,
    SPECS,
    Flag,
    GapReason,
    Kind,
    KindSpec,
    Stream,
    WireError,
    topic,
)

__all__ = [
    "GAP_PAYLOAD",
    "HEADER",
    "HELLO_KEYS",
    "KNOWN_FLAGS",
    "MAGIC",
    "MAX_HELLO",
    "MAX_PAYLOAD",
    "MAX_POSE_ITEMSIZE",
    "MAX_ROWS",
    "POSE_HEADER",
    "PROTOCOL_VERSION",
    "SPECS",
    "Body",
    "Dropped",
    "Flag",
    "Gap",
    "GapReason",
    "Hello",
    "Kind",
    "KindSpec",
    "Message",
    "Pose",
    "PoseFormat",
    "ProtocolError",
    "SeqReport",
    "SeqStats",
    "SeqStatus",
    "SequenceTracker",
    "Stream",
    "StreamIntake",
    "Taken",
    "WireError",
    "check_controls",
    "check_onsets",
    "check_stage_cues",
    "decode",
    "encode",
    "kind_of",
    "topic",
]
