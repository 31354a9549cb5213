"""The one payload of a result: the JSON API returns it, the page renders it."""

from __future__ import annotations

import csv
import io
from typing import TYPE_CHECKING, Any

from mesh_normal.triangle.normal import TriangleNormal

if TYPE_CHECKING:  # for the annotation only: mesh_normal.triangle.batch imports NumPy
    from mesh_normal.triangle.batch import BatchNormals


def normal_payload(result: TriangleNormal) -> dict[str, Any]:
    """A triangle's result with the API's field names; ``message`` only when there is one."""
    payload: dict[str, Any] = {
        "a": list(result.a),
        "b": list(result.b),
        "c": list(result.c),
        "order": result.order,
        "u": list(result.u),
        "v": list(result.v),
        "normal": list(result.normal),
        "magnitude": result.magnitude,
        "unit_normal": None if result.unit_normal is None else list(result.unit_normal),
        "area": result.area,
        "degenerate": result.degenerate,
    }
    if result.message is not None:
        payload["message"] = result.message
    return payload


def batch_payload(batch: BatchNormals, exact_rows: dict[int, TriangleNormal]) -> dict[str, Any]:
    """The batch answer, in input order; rows out of range come from their exact result."""
    normals = batch.normal.tolist()
    units = batch.unit_normal.tolist()
    magnitudes = batch.magnitude.tolist()
    areas = batch.area.tolist()
    degenerate = batch.degenerate.tolist()
    results: list[dict[str, Any]] = []
    for row in range(len(batch)):
        exact = exact_rows.get(row)
        if exact is not None:
            results.append(_batch_item(normal_payload(exact)))
            continue
        results.append(
            {
                "normal": normals[row],
                "unit_normal": None if degenerate[row] else units[row],
                "magnitude": magnitudes[row],
                "area": areas[row],
                "degenerate": degenerate[row],
            }
        )
    return {"results": results}


def _batch_item(payload: dict[str, Any]) -> dict[str, Any]:
    keys = ("normal", "unit_normal", "magnitude", "area", "degenerate")
    return {key: payload[key] for key in keys}


CSV_COLUMNS = [
    "order",
    "ax",
    "ay",
    "az",
    "bx",
    "by",
    "bz",
    "cx",
    "cy",
    "cz",
    "ux",
    "uy",
    "uz",
    "vx",
    "vy",
    "vz",
    "nx",
    "ny",
    "nz",
    "magnitude",
    "unit_x",
    "unit_y",
    "unit_z",
    "area",
    "degenerate",
    "message",
    "plane_a",
    "plane_b",
    "plane_c",
    "plane_d",
    "angle_degrees",
    "angle_radians",
    "exact_nx",
    "exact_ny",
    "exact_nz",
    "exact_magnitude_squared",
    "exact_magnitude",
    "exact_unit_x",
    "exact_unit_y",
    "exact_unit_z",
    "exact_area",
    "exact_plane_a",
    "exact_plane_b",
    "exact_plane_c",
    "exact_plane_d",
    "exact_plane_equation",
]


def _extra_values(payload: dict[str, Any]) -> list[Any]:
    """Plane, angle and exact forms (as their text, such as ``√286 / 2``); empty when absent."""
    plane = payload.get("plane") or {}
    angle = payload.get("angle") or {}
    exact = payload.get("exact") or {}
    exact_plane = plane.get("exact") or {}
    units = exact.get("unit_normal") or [{}, {}, {}]
    texts = [
        *(exact.get("normal") or [{}, {}, {}]),
        exact.get("magnitude_squared", {}),
        exact.get("magnitude", {}),
        *units,
        exact.get("area", {}),
        *(exact_plane.get(key, {}) for key in "abcd"),
    ]
    return [
        *(plane.get(key) for key in "abcd"),
        angle.get("degrees"),
        angle.get("radians"),
        *(item.get("text") for item in texts),
        exact_plane.get("equation"),
    ]


def payload_csv(payload: dict[str, Any]) -> str:
    """One header row and one result row; numbers round-trip, an out-of-range value is empty.

    The exact forms are text, as in the JSON (``5/2``, ``√286 / 2``); empty when left out.
    """
    unit = payload["unit_normal"] or [None, None, None]
    values = [
        payload["order"],
        *payload["a"],
        *payload["b"],
        *payload["c"],
        *payload["u"],
        *payload["v"],
        *payload["normal"],
        payload["magnitude"],
        *unit,
        payload["area"],
        str(payload["degenerate"]).lower(),
        payload.get("message", ""),
        *_extra_values(payload),
    ]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    writer.writerow(
        [
            "" if value is None else repr(value) if isinstance(value, float) else value
            for value in values
        ]
    )
    return out.getvalue()
