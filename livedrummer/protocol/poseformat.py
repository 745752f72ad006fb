"""Pose format: any structured dtype, described canonically and hashed.

The pose dtype belongs to the body engine and is opaque to the wire: :class:`PoseFormat`
turns it into a canonical JSON description and an 8-byte BLAKE2b hash, announced in READY and
repeated in every POSE header, so a display built against another dtype refuses the frame.
Limits: no Python objects, nesting depth and item size bounded (checked when read back).
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from livedrummer.errors import ProtocolError
from livedrummer.protocol.spec import MAX_POSE_ITEMSIZE, fail

_SCALAR = re.compile(r"^[<>|][biufcV?]\d{1,6}$")


def _describe(dtype: np.dtype[Any]) -> dict[str, Any]:
    if dtype.fields is None or dtype.names is None:
        raise ProtocolError(f"pose dtype: must be a structured dtype (got {dtype})")
    formats = []
    offsets = []
    for name in dtype.names:
        sub, offset = dtype.fields[name][:2]
        shape = list(sub.shape)
        base = sub.base
        if base.fields is not None:
            formats.append({"struct": _describe(base), "shape": shape})
        else:
            if base.hasobject or not _SCALAR.match(base.str):
                raise ProtocolError(f"pose dtype: field {name!r}: unsupported type {base.str}")
            formats.append({"type": base.str, "shape": shape})
        offsets.append(int(offset))
    return {
        "names": list(dtype.names),
        "formats": formats,
        "offsets": offsets,
        "itemsize": int(dtype.itemsize),
    }


def _build(desc: object, where: str, depth: int = 0) -> np.dtype[Any]:
    if depth > 8:
        raise fail(where, "nested too deep", depth)
    if not isinstance(desc, dict) or set(desc) != {"names", "formats", "offsets", "itemsize"}:
        raise fail(where, "expected {names, formats, offsets, itemsize}", desc)
    names, formats, offsets, itemsize = (
        desc["names"],
        desc["formats"],
        desc["offsets"],
        desc["itemsize"],
    )
    if not (isinstance(names, list) and isinstance(formats, list) and isinstance(offsets, list)):
        raise fail(where, "names, formats, offsets must be lists", desc)
    if not names or not len(names) == len(formats) == len(offsets) or len(names) > 4096:
        raise fail(where, "names, formats and offsets differ in length or are empty", desc)
    if not all(isinstance(n, str) and n for n in names) or len(set(names)) != len(names):
        raise fail(f"{where}.names", "expected distinct non-empty strings", names)
    if not all(type(o) is int and 0 <= o <= MAX_POSE_ITEMSIZE for o in offsets):
        raise fail(f"{where}.offsets", "expected integers in range", offsets)
    if type(itemsize) is not int or not 0 < itemsize <= MAX_POSE_ITEMSIZE:
        raise fail(f"{where}.itemsize", f"expected 1..{MAX_POSE_ITEMSIZE}", itemsize)
    built: list[Any] = []
    for name, fmt in zip(names, formats, strict=True):
        place = f"{where}.{name}"
        if not isinstance(fmt, dict) or set(fmt) not in ({"type", "shape"}, {"struct", "shape"}):
            raise fail(place, "expected {type|struct, shape}", fmt)
        shape = fmt["shape"]
        if (
            not isinstance(shape, list)
            or len(shape) > 8
            or not all(type(n) is int and 0 < n <= MAX_POSE_ITEMSIZE for n in shape)
        ):
            raise fail(f"{place}.shape", "expected a list of positive integers", shape)
        if "type" in fmt:
            typestr = fmt["type"]
            if not isinstance(typestr, str) or not _SCALAR.match(typestr):
                raise fail(f"{place}.type", "unsupported scalar type", typestr)
            try:
                base = np.dtype(typestr)
            except TypeError as exc:
                raise fail(f"{place}.type", "not a numpy type", typestr) from exc
        else:
            base = _build(fmt["struct"], place, depth + 1)
        if math.prod(shape) * base.itemsize > MAX_POSE_ITEMSIZE:
            raise fail(place, "field too large", shape)
        built.append((base, tuple(shape)) if shape else base)
    try:
        return np.dtype(
            {"names": names, "formats": built, "offsets": offsets, "itemsize": itemsize}
        )
    except (TypeError, ValueError) as exc:
        raise fail(where, f"inconsistent layout ({exc})", desc) from exc


def _canonical(desc: Mapping[str, Any]) -> str:
    return json.dumps(desc, separators=(",", ":"), sort_keys=True)


@dataclass(frozen=True)
class PoseFormat:
    """A pose dtype with its canonical description and 8-byte hash."""

    dtype: np.dtype[Any]
    hash: bytes

    @classmethod
    def from_dtype(cls, dtype: np.dtype[Any]) -> PoseFormat:
        desc = _describe(np.dtype(dtype))
        if desc["itemsize"] > MAX_POSE_ITEMSIZE:
            raise ProtocolError(f"pose dtype: itemsize {desc['itemsize']} too large")
        digest = hashlib.blake2b(_canonical(desc).encode(), digest_size=8).digest()
        return cls(_build(desc, "pose dtype"), digest)

    def to_json(self) -> dict[str, Any]:
        return {"descr": _describe(self.dtype), "hash": self.hash.hex()}

    @classmethod
    def from_json(cls, obj: object) -> PoseFormat:
        if not isinstance(obj, dict) or set(obj) != {"descr", "hash"}:
            raise fail("hello.pose", "expected {descr, hash}", obj)
        fmt = cls.from_dtype(_build(obj["descr"], "hello.pose.descr"))
        if obj["hash"] != fmt.hash.hex():
            raise fail(
                "hello.pose.hash", f"does not match the descr ({fmt.hash.hex()})", obj["hash"]
            )
        return fmt
