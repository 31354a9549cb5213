"""Analytic point clouds with their true outward (or upward) normals, made in the tests.

Each returns ``(points, normals)``: (n, 3) float64 each. ``grid`` rounds the points to multiples
of 2**-24, so that moving them by up to 2**27 (1.3e8) is exact.
"""

from __future__ import annotations

import numpy as np

GRID = 2.0**-24


def rounded(points: np.ndarray) -> np.ndarray:
    """Points on the 2**-24 grid: exactly representable after a move by 1e6 or 1e8."""
    return np.round(points / GRID) * GRID


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=1, keepdims=True)


def sphere(n: int, seed: int = 0, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    normals = _unit(np.random.default_rng(seed).normal(size=(n, 3)))
    return radius * normals, normals


def torus(
    n: int, seed: int = 0, major: float = 1.0, minor: float = 0.3
) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 2 * np.pi, n)
    # The tube's angle drawn in proportion to the area: denser on the outside.
    v = rng.uniform(0, 2 * np.pi, 4 * n)
    keep = rng.uniform(0, major + minor, 4 * n) < major + minor * np.cos(v)
    v = v[keep][:n]
    normals = np.stack([np.cos(u) * np.cos(v), np.sin(u) * np.cos(v), np.sin(v)], axis=1)
    ring = np.stack([major * np.cos(u), major * np.sin(u), np.zeros(n)], axis=1)
    return ring + minor * normals, normals


def cylinder(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """An open tube of radius 1 and height 2: normals away from the axis."""
    rng = np.random.default_rng(seed)
    u, z = rng.uniform(0, 2 * np.pi, n), rng.uniform(-1, 1, n)
    normals = np.stack([np.cos(u), np.sin(u), np.zeros(n)], axis=1)
    return normals + np.stack([np.zeros(n), np.zeros(n), z], axis=1), normals


def box(
    n: int, seed: int = 0, size: tuple[float, float, float] = (1.0, 1.0, 1.0)
) -> tuple[np.ndarray, np.ndarray]:
    """The surface of a box centred on the origin, points in proportion to each face's area."""
    rng = np.random.default_rng(seed)
    half = np.asarray(size) / 2
    areas = np.array([size[1] * size[2], size[0] * size[2], size[0] * size[1]])
    axis = rng.choice(3, size=n, p=areas / areas.sum())
    side = rng.choice([-1.0, 1.0], size=n)
    points = rng.uniform(-half, half, size=(n, 3))
    points[np.arange(n), axis] = side * half[axis]
    normals = np.zeros((n, 3))
    normals[np.arange(n), axis] = side
    return points, normals


def terrain(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A height field z = 0.1 sin(3x) cos(2y) over [-1, 1]**2: normals up."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
    z = 0.1 * np.sin(3 * x) * np.cos(2 * y)
    gradient_x, gradient_y = (
        0.3 * np.cos(3 * x) * np.cos(2 * y),
        -0.2 * np.sin(3 * x) * np.sin(2 * y),
    )
    normals = _unit(np.stack([-gradient_x, -gradient_y, np.ones(n)], axis=1))
    return np.stack([x, y, z], axis=1), normals


def near_edges(points: np.ndarray, size: tuple[float, float, float], margin: float) -> np.ndarray:
    """Points of :func:`box` within ``margin`` of an edge (two coordinates at their bounds)."""
    half = np.asarray(size) / 2
    at_bound = np.abs(np.abs(points) - half) < margin
    return at_bound.sum(axis=1) >= 2


def angles(normals: np.ndarray, truth: np.ndarray, unoriented: bool = False) -> np.ndarray:
    """Degrees between each row and the truth (between their lines if ``unoriented``)."""
    dots = np.einsum("ij,ij->i", normals, truth)
    if unoriented:
        dots = np.abs(dots)
    return np.degrees(np.arccos(np.clip(dots, -1.0, 1.0)))


def rmse(degrees: np.ndarray) -> float:
    return float(np.sqrt(np.mean(degrees**2)))
