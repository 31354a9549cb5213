"""Code to paste: the page's computation for the user's points, as ready-to-run snippets.

Every snippet starts from exactly the page's doubles (written with ``repr``, the shortest text
that reads back as the same double), follows the page's winding, and prints lines that are
easy to read back::

    normal = (6.0, 3.0, 2.0)
    magnitude = 7.0
    unit_normal = (0.8571428571428571, 0.42857142857142855, 0.2857142857142857)
    area = 3.5

A degenerate triangle prints ``degenerate: no unit normal`` instead of a unit normal. The page
rounds the exact result once; the snippets round at every float step, so for ordinary points
they agree to the last digit or so, and a snippet says so in a comment when its floats cannot
match the page (a sliver whose float cross product is off, values beyond the double range).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from textwrap import dedent
from typing import Any

#: Relative error of a float cross product that still counts as rounding noise: a few ulps
#: of |u||v| is normal, more means the triangle is a sliver (or the float |n| overflows).
FLOAT_NOISE = 1e-12

#: trimesh's ``tol.zero``: it reports faces with |n| at or below this as degenerate.
TRIMESH_ZERO = 1e-13


@dataclass(frozen=True, slots=True)
class Snippet:
    """One flavour of the code: ``language`` is a highlighting hint, ``code`` ready to run."""

    key: str
    title: str
    language: str
    code: str
    runs_in_tests: bool


Rationals = Sequence[Sequence[Fraction]]


def snippets(payload: dict[str, Any], typed: Rationals | None = None) -> list[Snippet]:
    """The snippets for one result of :func:`~app.calculator.payloads.normal_payload`.

    ``typed`` holds A, B, C as the exact decimals typed, when the page computed with them:
    the library snippet then passes them as fractions, to print the page's numbers.
    """
    return [
        Snippet("numpy", "NumPy", "python", _numpy(payload), True),
        Snippet("mesh_normal", "mesh_normal", "python", _mesh_normal(payload, typed), True),
        Snippet("python", "Pure Python", "python", _python(payload), True),
        Snippet("trimesh", "trimesh", "python", _trimesh(payload), True),
        Snippet("open3d", "Open3D", "python", _open3d(payload), False),
        Snippet("blender", "Blender (mathutils)", "python", _blender(payload), False),
    ]


# --- What every snippet shares ----------------------------------------------------------------


def _coordinates(point: Sequence[float]) -> str:
    return ", ".join(repr(float(x)) for x in point)


def _swapped(payload: dict[str, Any]) -> bool:
    return bool(payload["order"] == "ACB")


def _code(*parts: str | None) -> str:
    """Join comment lines and dedented blocks into one script, ending in a newline."""
    return "\n\n".join(dedent(part).strip("\n") for part in parts if part) + "\n"


def _header(payload: dict[str, Any], what: str) -> str:
    lines = [f"# {what}"]
    if _swapped(payload):
        lines.append("# Winding A, C, B (swapped on the page): the corners go in that order,")
        lines.append("# so the normal flips.")
    lines.extend(_float_note(payload))
    return "\n".join(lines)


def _float_note(payload: dict[str, Any]) -> list[str]:
    """A comment when plain floats cannot give the page's numbers for these points."""
    if _out_of_range(payload):
        return _warning("some of the page's values are beyond the double range")
    if _float_normal_is_off(payload):
        return _warning("the float normal or its length is off in more than its last digits")
    if _float_cross(payload) != tuple(payload["normal"]):
        return [
            "# The page rounds the exact normal once; floats round at every step, so the",
            "# last digits here may differ.",
        ]
    return []


def _warning(reason: str) -> list[str]:
    return [
        "# Note: the page's numbers are exact, rounded once; the floats here may differ:",
        f"# {reason}.",
    ]


def _out_of_range(payload: dict[str, Any]) -> bool:
    values = [
        *payload["u"],
        *payload["v"],
        *payload["normal"],
        payload["magnitude"],
        payload["area"],
    ]
    return any(value is None for value in values)


def _float_normal_is_off(payload: dict[str, Any]) -> bool:
    """Whether the naive double normal, or its squared length, is beyond rounding noise."""
    normal = _float_cross(payload)
    if not all(map(math.isfinite, normal)):
        return True
    error = max(abs(x - y) for x, y in zip(normal, payload["normal"], strict=True))
    if error > FLOAT_NOISE * max(map(abs, payload["normal"])):
        return True
    squares = sum(x * x for x in normal)  # what np.linalg.norm sums, unscaled
    return any(normal) and not sys.float_info.min <= squares < math.inf


def _float_cross(payload: dict[str, Any]) -> tuple[float, float, float]:
    """(second - first) x (third - first) in plain doubles, in the payload's winding."""
    a, b, c = payload["a"], payload["b"], payload["c"]
    second, third = (c, b) if _swapped(payload) else (b, c)
    ux, uy, uz = (second[i] - a[i] for i in range(3))
    vx, vy, vz = (third[i] - a[i] for i in range(3))
    return (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)


def _edges(payload: dict[str, Any]) -> str:
    """u and v as the page defines them, honouring the winding."""
    if _swapped(payload):
        return "u = c - a  # winding A, C, B: u = C - A\nv = b - a  # and v = B - A\n"
    return "u = b - a\nv = c - a\n"


def _face(payload: dict[str, Any]) -> str:
    return "[[0, 2, 1]]  # A, C, B" if _swapped(payload) else "[[0, 1, 2]]"


_REPORT = """
    print("normal =", {normal})
    print("magnitude =", magnitude)
    if magnitude == 0.0:
        print("degenerate: no unit normal")
    else:
        print("unit_normal =", {unit})
    print("area =", {area})
"""


def _report(normal: str, unit: str, area: str = "magnitude / 2") -> str:
    return _REPORT.format(normal=normal, unit=unit, area=area)


# --- The flavours -----------------------------------------------------------------------------


def _numpy(payload: dict[str, Any]) -> str:
    a, b, c = (_coordinates(payload[name]) for name in "abc")
    return _code(
        _header(payload, "Triangle normal with NumPy: n = u x v, |n|, n / |n| and area |n| / 2."),
        f"""
        import numpy as np

        a = np.array([{a}])
        b = np.array([{b}])
        c = np.array([{c}])
        """,
        _edges(payload),
        """
        n = np.cross(u, v)
        magnitude = float(np.linalg.norm(n))
        """,
        _report("tuple(n.tolist())", "tuple((n / magnitude).tolist())"),
    )


def _fraction_coordinates(point: Sequence[Fraction]) -> str:
    return ", ".join(f'F("{x}")' for x in point)


def _mesh_normal(payload: dict[str, Any], typed: Rationals | None = None) -> str:
    """This project's library: the page's own computation, so its numbers to the last bit."""
    if typed is not None and any(Fraction(float(x)) != x for point in typed for x in point):
        return _mesh_normal_rational(payload, typed)
    a, b, c = (_coordinates(payload[name]) for name in "abc")
    lines = [
        "# Triangle normal with mesh_normal, the library behind this page: exact and",
        "# rounded once, so it prints the page's numbers to the last digit.",
    ]
    if _out_of_range(payload):
        lines.append("# A value beyond the double range prints as None (the page's out of range).")
    swap = ", swap_winding=True)  # winding A, C, B: the normal flips" if _swapped(payload) else ")"
    return _code(
        "\n".join(lines),
        f"""
        import mesh_normal as mn

        a = ({a})
        b = ({b})
        c = ({c})

        r = mn.triangle_normal(a, b, c{swap}
        print("normal =", r.normal)
        print("magnitude =", r.magnitude)
        if r.unit_normal is None:
            print("degenerate: no unit normal")
        else:
            print("unit_normal =", r.unit_normal)
        print("area =", r.area)
        """,
    )


def _mesh_normal_rational(payload: dict[str, Any], typed: Rationals) -> str:
    """The library on the exact decimals typed (0.1 is 1/10, not the double nearest it)."""
    a, b, c = (_fraction_coordinates(point) for point in typed)
    swap = ", swap_winding=True)  # winding A, C, B: the normal flips" if _swapped(payload) else ")"
    return _code(
        "# Triangle normal with mesh_normal, the library behind this page, on the decimals\n"
        "# as typed (exact fractions: 0.1 is 1/10), rounded once: the page's numbers to the\n"
        "# last digit.",
        f"""
        from fractions import Fraction as F

        from mesh_normal.triangle.normal import rational_triangle_normal

        a = ({a})
        b = ({b})
        c = ({c})

        r = rational_triangle_normal(a, b, c{swap}
        print("normal =", r.normal)
        print("magnitude =", r.magnitude)
        if r.unit_normal is None:
            print("degenerate: no unit normal")
        else:
            print("unit_normal =", r.unit_normal)
        print("area =", r.area)
        """,
    )


def _python(payload: dict[str, Any]) -> str:
    a, b, c = (_coordinates(payload[name]) for name in "abc")
    second, third = ("c", "b") if _swapped(payload) else ("b", "c")
    return _code(
        _header(payload, "Triangle normal in pure Python: the cross product written out."),
        f"""
        import math

        a = ({a})
        b = ({b})
        c = ({c})

        u = tuple({second}[i] - a[i] for i in range(3))
        v = tuple({third}[i] - a[i] for i in range(3))
        n = (
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        )
        magnitude = math.hypot(*n)  # sqrt(nx**2 + ny**2 + nz**2), without overflow
        """,
        _report("n", "tuple(x / magnitude for x in n)"),
    )


def _trimesh(payload: dict[str, Any]) -> str:
    a, b, c = (_coordinates(payload[name]) for name in "abc")
    face = _face(payload)
    return _code(
        _header(payload, "Triangle normal with trimesh: one face, kept as given (process=False)."),
        _trimesh_tolerance_note(payload),
        f"""
        import numpy as np
        import trimesh

        vertices = [
            [{a}],  # A
            [{b}],  # B
            [{c}],  # C
        ]
        faces = {face}
        mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)

        # trimesh crosses (B - A) x (C - B): the same vector as (B - A) x (C - A).
        n = trimesh.triangles.cross(mesh.triangles)[0]
        magnitude = float(np.linalg.norm(n))
        """,
        # face_normals holds (0, 0, 0) for a face trimesh finds degenerate.
        _report(
            "tuple(n.tolist())", "tuple(mesh.face_normals[0].tolist())", area="float(mesh.area)"
        ),
    )


def _trimesh_tolerance_note(payload: dict[str, Any]) -> str | None:
    magnitude = payload["magnitude"]
    if payload["degenerate"] or magnitude is None or magnitude > TRIMESH_ZERO:
        return None
    return (
        "# trimesh counts faces with |n| <= 1e-13 as degenerate (tol.zero), so its unit\n"
        "# normal here is (0, 0, 0) although the page finds one.\n"
    )


def _open3d(payload: dict[str, Any]) -> str:
    a, b, c = (_coordinates(payload[name]) for name in "abc")
    face = _face(payload)
    return _code(
        _header(payload, "Triangle normal with Open3D (legacy TriangleMesh)."),
        f"""
        import numpy as np
        import open3d as o3d

        vertices = np.array([
            [{a}],  # A
            [{b}],  # B
            [{c}],  # C
        ])
        faces = {face}
        triangles = np.array(faces, dtype=np.int32)
        mesh = o3d.geometry.TriangleMesh()
        mesh.vertices = o3d.utility.Vector3dVector(vertices)
        mesh.triangles = o3d.utility.Vector3iVector(triangles)

        mesh.compute_triangle_normals(normalized=False)  # raw (B - A) x (C - A)
        n = np.asarray(mesh.triangle_normals)[0].copy()
        magnitude = float(np.linalg.norm(n))
        mesh.compute_triangle_normals()  # normalized=True: unit normals
        # A degenerate face gets (0, 0, 0) or (0, 0, 1), by version: hence the check below.
        """,
        _report(
            "tuple(n.tolist())",
            "tuple(np.asarray(mesh.triangle_normals)[0].tolist())",
            area="mesh.get_surface_area()",
        ),
    )


def _blender(payload: dict[str, Any]) -> str:
    a, b, c = (_coordinates(payload[name]) for name in "abc")
    corners = "a, c, b" if _swapped(payload) else "a, b, c"
    return _code(
        _header(payload, "Triangle normal in Blender's Python console (Scripting workspace)."),
        f"""
        # mathutils stores single-precision floats: expect about 7 significant digits,
        # and no values beyond about 3.4e38.
        from mathutils import Vector
        from mathutils.geometry import area_tri, normal

        a = Vector(({a}))
        b = Vector(({b}))
        c = Vector(({c}))
        """,
        _edges(payload),
        """
        n = u.cross(v)
        magnitude = n.length
        """,
        f"""
        # geometry.normal returns the unit normal, by the same counter-clockwise
        # (right-hand) rule as the page; it is (0, 0, 0) for a degenerate triangle.
        print("normal =", tuple(n))
        print("magnitude =", magnitude)
        if magnitude == 0.0:
            print("degenerate: no unit normal")
        else:
            print("unit_normal =", tuple(normal({corners})))
        print("area =", area_tri({corners}))
        """,
    )
