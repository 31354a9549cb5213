"""The point formats' file names, apart from the readers (no NumPy here: the web app names
them as it starts)."""

from __future__ import annotations

#: Extension (lower case, with the dot) to the point format it names.
POINT_SUFFIXES: dict[str, str] = {
    ".ply": "ply",
    ".pcd": "pcd",
    ".las": "las",
    ".laz": "las",
    **dict.fromkeys((".xyz", ".xyzn", ".xyzrgb", ".pts", ".txt", ".csv", ".asc"), "xyz"),
}
