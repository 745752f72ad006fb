"""A VRM's own expressions as the face shapes the body drives (blink, reactions, looks).

Why this shape. :mod:`livedrummer.body.face` speaks of a few shapes by our names
(:data:`~livedrummer.body.face.FACES`); a VRM file carries its own, as sums of morph targets:

* VRM 1.0: ``VRMC_vrm.expressions.preset`` (and ``custom``), each with ``morphTargetBinds``
  ``{node, index, weight 0..1}``;
* VRM 0.x: ``VRM.blendShapeMaster.blendShapeGroups``, each with a ``presetName`` and
  ``binds`` ``{mesh, index, weight 0..100}`` (a mesh, so every node showing that mesh).

:data:`NAMES` says which of the file's expressions becomes which of ours, first found wins
(VRM 0.x has no "surprised": its open "o" mouth stands in; a blink missing as one expression
is the sum of its left and right ones). The morph targets themselves are read by
:mod:`~livedrummer.avatar.gltf` as position deltas in the file's displayed frame;
:func:`vrm_faces` sums each expression's binds there, and the retargeting turns and scales
them with the vertices. A bad bind (an unknown node or target) is skipped with a log line,
not an error: a face is decoration. Limits: material colour and texture-transform binds are
ignored; a VRM 1.0 look-at of type ``bone`` (eye bones) is not drawn, the eyes riding on the
head (its ``lookLeft``... expressions, when present, are).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from livedrummer.avatar.gltf import GltfScene

log = logging.getLogger(__name__)

#: our face -> (VRM 1.0 expression names, VRM 0.x preset or group names), in preference order
NAMES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "blink": (("blink",), ("blink",)),
    "happy": (("happy",), ("joy", "fun")),
    "surprised": (("surprised", "oh"), ("surprised", "o")),
    "look_left": (("lookLeft",), ("lookleft",)),
    "look_right": (("lookRight",), ("lookright",)),
    "look_up": (("lookUp",), ("lookup",)),
    "look_down": (("lookDown",), ("lookdown",)),
}
_PAIRS = {"blink": (("blinkLeft", "blinkRight"), ("blink_l", "blink_r"))}

Binds = list[tuple[int, int, float]]  # (node, morph target, weight 0..1)


def _vrm1(ext: dict[str, Any]) -> dict[str, Binds]:
    exprs = ext.get("VRMC_vrm", {}).get("expressions", {})
    out: dict[str, Binds] = {}
    for group in ("custom", "preset"):  # a preset wins over a custom of the same name
        for name, e in (exprs.get(group) or {}).items():
            if isinstance(e, dict):
                binds = [b for b in e.get("morphTargetBinds") or [] if isinstance(b, dict)]
                out[str(name)] = [
                    (int(b.get("node", -1)), int(b.get("index", -1)), float(b.get("weight", 1.0)))
                    for b in binds
                ]
    return out


def _vrm0(ext: dict[str, Any], scene: GltfScene) -> dict[str, Binds]:
    groups = ext.get("VRM", {}).get("blendShapeMaster", {}).get("blendShapeGroups") or []
    out: dict[str, Binds] = {}
    for g in groups:
        if not isinstance(g, dict):
            continue
        binds: Binds = []
        for b in g.get("binds") or []:
            if not isinstance(b, dict):
                continue
            for node in scene.mesh_nodes.get(int(b.get("mesh", -1)), ()):
                binds.append((node, int(b.get("index", -1)), float(b.get("weight", 100.0)) / 100))
        for key in (str(g.get("presetName") or "").lower(), str(g.get("name") or "").lower()):
            if key and key != "unknown" and key not in out:
                out[key] = binds
    return out


def vrm_faces(scene: GltfScene) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Our face name -> (vertex indices, summed deltas in the file's displayed frame), for
    the expressions this file has (see the module docstring)."""
    ext = scene.extensions
    if "VRMC_vrm" in ext:
        found, version = _vrm1(ext), 0
    elif "VRM" in ext:
        found, version = _vrm0(ext, scene), 1
    else:
        return {}
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for ours, names in NAMES.items():
        binds = next((found[n] for n in names[version] if n in found), None)
        if binds is None and ours in _PAIRS and all(n in found for n in _PAIRS[ours][version]):
            binds = [b for n in _PAIRS[ours][version] for b in found[n]]
        if not binds:
            continue
        summed = _sum(scene, binds, ours)
        if summed is not None:
            out[ours] = summed
    return out


def _sum(scene: GltfScene, binds: Binds, name: str) -> tuple[np.ndarray, np.ndarray] | None:
    idx, deltas = [], []
    for node, target, weight in binds:
        got = scene.morphs.get((node, target))
        if got is None:
            log.info(
                "%s: expression for %s binds node %d target %d, which has none: skipped",
                scene.source,
                name,
                node,
                target,
            )
            continue
        idx.append(got[0])
        deltas.append(got[1] * weight)
    if not idx:
        return None
    return np.concatenate(idx), np.concatenate(deltas)
