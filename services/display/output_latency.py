"""The latency after an output stream's buffer, where PortAudio does not know it (JACK).

PortAudio's JACK host reports an output latency of 0 when the stream is opened (its ports are
connected only when it starts), while JACK's playback ports add their own (one period, two in
JACK's default asynchronous mode).
:func:`output_latency_s` asks JACK for it directly, through libjack (``libjack.so.0``, there
wherever PortAudio talks to JACK): the playback latency of the server's ``system:playback_1``,
the port a PortAudio stream connects to by default. PortAudio's own figure, once it has
connected its ports, is one period short of it where JACK runs asynchronously (its default:
the playback ports add two periods, PortAudio said one; measured through a recording JACK
client, a sound came 2.6 ms late at 128-frame periods). Other host APIs: PortAudio's figure.

Limits: a stream routed to another port than ``system:playback_1`` gets that port's latency
only where it equals it; no server, no library: PortAudio's figure (0 for JACK).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
from typing import Any

log = logging.getLogger("livedrummer.display")

_NO_START_SERVER = 0x01
_PLAYBACK_LATENCY = 1
PLAYBACK_PORT = b"system:playback_1"


def jack_playback_latency_s(port: bytes = PLAYBACK_PORT) -> float | None:
    """``port``'s playback latency (max of its range) in seconds, or None without JACK."""
    name = ctypes.util.find_library("jack") or "libjack.so.0"
    try:
        lib = ctypes.CDLL(name)
    except OSError:
        return None
    lib.jack_client_open.restype = ctypes.c_void_p
    lib.jack_port_by_name.restype = ctypes.c_void_p
    lib.jack_port_by_name.argtypes = [ctypes.c_void_p, ctypes.c_char_p]
    lib.jack_get_sample_rate.restype = ctypes.c_uint32
    lib.jack_get_sample_rate.argtypes = [ctypes.c_void_p]
    lib.jack_port_get_latency_range.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p]
    lib.jack_client_close.argtypes = [ctypes.c_void_p]
    status = ctypes.c_int(0)
    client = lib.jack_client_open(b"ldlatency", _NO_START_SERVER, ctypes.byref(status))
    if not client:
        return None
    try:
        handle = lib.jack_port_by_name(client, port)
        if not handle:
            return None
        span = (ctypes.c_uint32 * 2)()
        lib.jack_port_get_latency_range(handle, _PLAYBACK_LATENCY, span)
        return float(span[1]) / float(lib.jack_get_sample_rate(client))
    finally:
        lib.jack_client_close(client)


def jack_period() -> int:
    """The JACK server's buffer size (frames), or 0 without JACK."""
    name = ctypes.util.find_library("jack") or "libjack.so.0"
    try:
        lib = ctypes.CDLL(name)
    except OSError:
        return 0
    lib.jack_client_open.restype = ctypes.c_void_p
    lib.jack_get_buffer_size.restype = ctypes.c_uint32
    lib.jack_get_buffer_size.argtypes = [ctypes.c_void_p]
    lib.jack_client_close.argtypes = [ctypes.c_void_p]
    status = ctypes.c_int(0)
    client = lib.jack_client_open(b"ldperiod", _NO_START_SERVER, ctypes.byref(status))
    if not client:
        return 0
    try:
        return int(lib.jack_get_buffer_size(client))
    finally:
        lib.jack_client_close(client)


def output_period(stream: Any) -> int:
    """How many samples the device takes from ``stream``'s FIFO at a time, where known:
    JACK's buffer size for a JACK stream, else 0."""
    import sounddevice as sd

    try:
        api = sd.query_hostapis(sd.query_devices(stream.device)["hostapi"])["name"]
    except (ValueError, sd.PortAudioError, KeyError, TypeError):
        return 0
    return jack_period() if "JACK" in str(api) else 0


def output_latency_s(stream: Any) -> float:
    """The time from a sample leaving ``stream``'s buffer (a sounddevice stream) to its
    being heard: JACK's playback latency for a JACK stream, else PortAudio's figure."""
    import sounddevice as sd

    reported = float(stream.latency)
    try:
        api = sd.query_hostapis(sd.query_devices(stream.device)["hostapi"])["name"]
    except (ValueError, sd.PortAudioError, KeyError, TypeError):
        return reported
    if "JACK" in str(api):  # PortAudio says 0, or the ports' latency once it has connected them
        got = jack_playback_latency_s()
        if got is not None:
            log.debug("JACK playback latency %.2f ms", got * 1000)
            return got
    return reported
