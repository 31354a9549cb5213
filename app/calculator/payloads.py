"""The one payload of a result: the JSON API returns it, the page renders it."""

from __future__ import annotations

import csv
import io
from typing import Any

from mesh_normal.batch import BatchNormals
from mesh_normal.triangle import TriangleNormal


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
]


def payload_csv(payload: dict[str, Any]) -> str:
    """One header row and one result row; numbers round-trip, an out-of-range value is empty."""
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
