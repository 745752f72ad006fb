"""A 5x7 bitmap font (upper-case letters, digits, space and ``-+:./()[]=,``) for labels.

The overlays label lanes and legends with two or three characters; a font renderer (FreeType)
would be a dependency for that, so the glyphs are written here, one string of ``#`` and ``.``
per row. :func:`text_pixels` turns a text into the (row, column) offsets of its lit pixels,
cached, so painting a label is one fancy-indexed assignment. Characters the font lacks are
drawn blank (a label is decoration, never data).
"""

from __future__ import annotations

import functools

import numpy as np

GLYPH_W = 5
GLYPH_H = 7
ADVANCE = GLYPH_W + 1  # one blank column between characters

_ROWS: dict[str, str] = {
    "A": ".###. #...# #...# ##### #...# #...# #...#",
    "B": "####. #...# #...# ####. #...# #...# ####.",
    "C": ".###. #...# #.... #.... #.... #...# .###.",
    "D": "####. #...# #...# #...# #...# #...# ####.",
    "E": "##### #.... #.... ####. #.... #.... #####",
    "F": "##### #.... #.... ####. #.... #.... #....",
    "G": ".###. #...# #.... #.### #...# #...# .####",
    "H": "#...# #...# #...# ##### #...# #...# #...#",
    "I": ".###. ..#.. ..#.. ..#.. ..#.. ..#.. .###.",
    "J": "..### ...#. ...#. ...#. ...#. #..#. .##..",
    "K": "#...# #..#. #.#.. ##... #.#.. #..#. #...#",
    "L": "#.... #.... #.... #.... #.... #.... #####",
    "M": "#...# ##.## #.#.# #.#.# #...# #...# #...#",
    "N": "#...# #...# ##..# #.#.# #..## #...# #...#",
    "O": ".###. #...# #...# #...# #...# #...# .###.",
    "P": "####. #...# #...# ####. #.... #.... #....",
    "Q": ".###. #...# #...# #...# #.#.# #..#. .##.#",
    "R": "####. #...# #...# ####. #.#.. #..#. #...#",
    "S": ".#### #.... #.... .###. ....# ....# ####.",
    "T": "##### ..#.. ..#.. ..#.. ..#.. ..#.. ..#..",
    "U": "#...# #...# #...# #...# #...# #...# .###.",
    "V": "#...# #...# #...# #...# #...# .#.#. ..#..",
    "W": "#...# #...# #...# #.#.# #.#.# #.#.# .#.#.",
    "X": "#...# #...# .#.#. ..#.. .#.#. #...# #...#",
    "Y": "#...# #...# .#.#. ..#.. ..#.. ..#.. ..#..",
    "Z": "##### ....# ...#. ..#.. .#... #.... #####",
    "0": ".###. #...# #..## #.#.# ##..# #...# .###.",
    "1": "..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###.",
    "2": ".###. #...# ....# ...#. ..#.. .#... #####",
    "3": "##### ...#. ..#.. ...#. ....# #...# .###.",
    "4": "...#. ..##. .#.#. #..#. ##### ...#. ...#.",
    "5": "##### #.... ####. ....# ....# #...# .###.",
    "6": "..##. .#... #.... ####. #...# #...# .###.",
    "7": "##### ....# ...#. ..#.. .#... .#... .#...",
    "8": ".###. #...# #...# .###. #...# #...# .###.",
    "9": ".###. #...# #...# .#### ....# ...#. .##..",
    "-": "..... ..... ..... ##### ..... ..... .....",
    "+": "..... ..#.. ..#.. ##### ..#.. ..#.. .....",
    " ": "..... ..... ..... ..... ..... ..... .....",
    ":": "..... ..#.. ..#.. ..... ..#.. ..#.. .....",
    ".": "..... ..... ..... ..... ..... .##.. .##..",
    "/": "....# ...#. ...#. ..#.. .#... .#... #....",
    "(": "...#. ..#.. .#... .#... .#... ..#.. ...#.",
    ")": ".#... ..#.. ...#. ...#. ...#. ..#.. .#...",
    "[": ".###. .#... .#... .#... .#... .#... .###.",
    "]": ".###. ...#. ...#. ...#. ...#. ...#. .###.",
    "=": "..... ..... ##### ..... ##### ..... .....",
    ",": "..... ..... ..... ..... .##.. ..#.. .#...",
}

#: character -> bool (7, 5) bitmap
GLYPHS: dict[str, np.ndarray] = {
    ch: np.array([[c == "#" for c in row] for row in rows.split()], bool)
    for ch, rows in _ROWS.items()
}


def text_size(text: str, scale: int = 1) -> tuple[int, int]:
    """(height, width) in pixels of ``text`` drawn at ``scale``."""
    return GLYPH_H * scale, max(len(text) * ADVANCE - 1, 0) * scale


@functools.lru_cache(maxsize=256)
def text_pixels(text: str, scale: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Row and column offsets (from the text's top-left) of the lit pixels of ``text``."""
    blank = GLYPHS[" "]
    bitmap = np.zeros((GLYPH_H, max(len(text) * ADVANCE, 1)), bool)
    for i, ch in enumerate(text.upper()):
        bitmap[:, i * ADVANCE : i * ADVANCE + GLYPH_W] = GLYPHS.get(ch, blank)
    if scale > 1:
        bitmap = np.kron(bitmap, np.ones((scale, scale), bool))
    rows, cols = np.nonzero(bitmap)
    rows.flags.writeable = False
    cols.flags.writeable = False
    return rows, cols
