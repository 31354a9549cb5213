"""The reports' base: frozen dataclasses of plain Python values, with their JSON.

The reports are stdlib dataclasses, not pydantic models, so that ``mn.analyse`` in a new process
does not pay for pydantic (its import and the models' schemas cost more than reading and
checking a 56,000-face mesh). Each field's ``metadata`` holds its description and limits in
pydantic's words (``description``, ``ge``, ``min_length``...): the web app's OpenAPI schema is
generated from them (``pydantic.TypeAdapter(MeshReport).json_schema()``), and the same adapter
validates a report's JSON in the tests.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

#: How many indices (faces, components, points) a list in a report holds at most; counts are
#: full.
INDEX_LIST_LIMIT = 100
#: A measure that may overflow the double range: ``None`` (JSON ``null``) when it does.
Measure = float | None
#: A float that is always finite (a coordinate of a checked mesh, a fixed angle).
Finite = float


def described(description: str, **limits: object) -> Any:
    """A report field: its description and limits, as the JSON schema states them."""
    return dataclasses.field(metadata={"description": description, **limits})


def _plain(value: object, finite: bool) -> object:
    """``value`` as plain Python: a NumPy scalar as its Python value, lists item by item, and a
    float that is not finite as ``None`` (so a report never holds NaN or infinity), or a
    ``ValueError`` where it must be ``finite``."""
    if type(value).__module__ == "numpy":
        value = value.item()  # type: ignore[attr-defined]
    if isinstance(value, float) and not math.isfinite(value):
        if finite:
            raise ValueError(f"{value} where a finite number must be.")
        return None
    if isinstance(value, list) and not all(type(item) in (int, str) for item in value):
        return [_plain(item, finite) for item in value]
    return value


class Record:
    """A report's part: frozen, plain values only, every float finite or ``None``; a ``Finite``
    field refuses a float that is not finite (``ValueError``)."""

    __slots__ = ()
    # Read by pydantic when the web app and the tests build the schema and validate JSON.
    __pydantic_config__: ClassVar[dict[str, object]] = {
        "extra": "forbid",
        "ser_json_inf_nan": "null",
    }

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):  # type: ignore[arg-type]
            value = getattr(self, field.name)
            # A field typed ``Finite`` (above) holds a number that is
            # always finite; the annotation is read as written (the reports' modules postpone them).
            plain = _plain(value, "Finite" in str(field.type))
            if plain is not value:
                object.__setattr__(self, field.name, plain)

    def to_dict(self) -> dict[str, Any]:
        """The report as nested dicts and lists (what :meth:`to_json` writes)."""
        return dataclasses.asdict(self)  # type: ignore[call-overload, no-any-return]

    def to_json(self, indent: int | None = None) -> str:
        """The report's JSON: what the web app's API answers for it."""
        from pydantic_core import to_json  # only when JSON is asked for

        return to_json(self, indent=indent, inf_nan_mode="null").decode()
