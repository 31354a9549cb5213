"""Where a 3D view's camera stands: the up axis a file implies, and a three-quarter view from
far enough that the whole drawing is in the picture. The mesh and point-cloud pages share it.

Plotly's scenes (``aspectmode: "data"``) place the data in scene units (:class:`Scene`); a
camera is an eye, a centre and an up vector in those units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: The up axis each format implies: glTF is Y-up by its specification and most OBJ exporters
#: write Y-up too; STL, PLY, OFF and 3MF come mostly from CAD and printing, which are Z-up, and
#: so are scans (LAS, PCD, XYZ: the ground is x, y).
FORMAT_UP = {"gltf": "y", "glb": "y", "obj": "y"}
DEFAULT_UP = "z"
#: Where the camera looks from for each up axis: a three-quarter view from the front and above
#: (a direction; :func:`cameras` sets its distance).
CAMERAS: dict[str, dict[str, dict[str, float]]] = {
    "x": {"up": {"x": 1, "y": 0, "z": 0}, "eye": {"x": 0.9, "y": 1.25, "z": 1.25}},
    "y": {"up": {"x": 0, "y": 1, "z": 0}, "eye": {"x": 1.25, "y": 0.9, "z": 1.25}},
    "z": {"up": {"x": 0, "y": 0, "z": 1}, "eye": {"x": 1.25, "y": -1.25, "z": 0.9}},
}
#: Half of Plotly's vertical field of view (plotly.js's 3D scenes: 45 degrees), and the room
#: left around the drawing when it is framed. A canvas taller than wide (a phone) narrows the
#: horizontal field: the page moves the camera back by as much (static/js/view3d.js, fitted).
HALF_FIELD = math.pi / 8
FRAME_MARGIN = 1.15
#: The highest a camera looks from (the sine of its angle above the horizon).
MAX_ELEVATION = 0.8


def up_axis(file_format: str) -> str:
    """The axis a file of this format is drawn with upward: "y" for glTF and OBJ, else "z"."""
    return FORMAT_UP.get(file_format, DEFAULT_UP)


@dataclass(frozen=True)
class Scene:
    """How Plotly places the drawn points in its scene (``aspectmode: "data"``): each axis's
    data range, centred on its middle, divided by the ranges' geometric mean; a range of zero
    counts as 2 (Plotly's autorange of one value, v - 1 to v + 1)."""

    middle: NDArray[np.float64]
    unit: float  # data units per scene unit
    radius: float  # the scene box's bounding sphere, in scene units

    @classmethod
    def of(cls, points: NDArray[np.float64]) -> Scene:
        if not len(points):
            return cls(np.zeros(3), 1.0, math.sqrt(3) / 2)
        low, high = points.min(axis=0), points.max(axis=0)
        ranges = np.where(high > low, high - low, 2.0)
        unit = float(np.exp(np.log(ranges).mean()))
        return cls((low + high) / 2, unit, float(np.linalg.norm(ranges / unit)) / 2)

    def place(self, point: NDArray[np.float64]) -> dict[str, float]:
        return vector((point - self.middle) / self.unit)

    @property
    def distance(self) -> float:
        """How far from the centre the camera sees the whole box with a margin."""
        return FRAME_MARGIN * self.radius / math.sin(HALF_FIELD)


def vector(values: NDArray[np.float64]) -> dict[str, float]:
    """A Plotly vector ``{"x", "y", "z"}``, five decimals of a scene unit."""
    x, y, z = (round(float(value), 5) for value in values)
    return {"x": x, "y": y, "z": z}


def cameras(
    scene: Scene, points: NDArray[np.float64], towards: NDArray[np.float64] | None = None
) -> dict[str, dict[str, Any]]:
    """The camera for each up axis: from the three-quarter view (turned towards ``towards``, a
    direction in scene units, when one is given), just far enough that every point is in the
    picture with a margin (:func:`framing`)."""
    placed = (points - scene.middle) / scene.unit if len(points) else np.zeros((1, 3))
    views = {}
    for up, camera in CAMERAS.items():
        upward = np.array([camera["up"][axis] for axis in "xyz"], dtype=float)
        default = np.array([camera["eye"][axis] for axis in "xyz"])
        direction = default / np.linalg.norm(default)
        if towards is not None and np.any(towards):
            direction = direction + 2 * towards / np.linalg.norm(towards)
            direction = below_the_pole(direction / np.linalg.norm(direction), upward)
        views[up] = {
            "up": camera["up"],
            "center": {"x": 0.0, "y": 0.0, "z": 0.0},
            "eye": vector(direction * framing(direction, upward, placed)),
        }
    return views


def below_the_pole(direction: NDArray[np.float64], up: NDArray[np.float64]) -> NDArray[np.float64]:
    """``direction`` at most MAX_ELEVATION (a sine) above or below the horizon: a camera
    looking straight down the up axis would lose which way is up."""
    height = float(direction @ up)
    if abs(height) <= MAX_ELEVATION:
        return direction
    level = direction - height * up
    level /= np.linalg.norm(level)
    return level * math.sqrt(1 - MAX_ELEVATION**2) + math.copysign(MAX_ELEVATION, height) * up


def framing(
    direction: NDArray[np.float64], up: NDArray[np.float64], placed: NDArray[np.float64]
) -> float:
    """How far along ``direction`` from the scene's centre the camera must stand for every
    point (in scene units) to be drawn within 1 / FRAME_MARGIN of the picture's middle, in a
    square picture: a point p is at p.right / (d - p.direction) times the focal length."""
    right = np.cross(-direction, up)
    right /= np.linalg.norm(right)
    upward = np.cross(right, -direction)
    across = np.maximum(np.abs(placed @ right), np.abs(placed @ upward))
    focal = 1 / math.tan(HALF_FIELD)
    return float(np.max(placed @ direction + focal * FRAME_MARGIN * across))
