"""A glTF asset made ready for trimesh: extensions checked, buffers gathered, integers decoded.

Whatever came in (GLB, ``.gltf`` with ``data:`` URIs, ``.gltf`` with its ``.bin`` files from
a ``.zip``), it leaves as one GLB whose single binary chunk holds every buffer, so trimesh's
GLB reader sees one shape of input and never opens a file itself. On the way:

- every ``extensionsRequired`` entry we cannot honour is a 415 naming it (trimesh would
  otherwise read such accessors as zeros, or fail with an index error);
- normalized integer accessors (``KHR_mesh_quantization``) become float32 per the glTF
  specification, which trimesh does not do (it would read an int16 position as up to 32767);
  ``COLOR_0`` bytes and shorts stay integers, as vertex colours are kept.
"""

from __future__ import annotations

import base64
import binascii
import dataclasses
import importlib.util
import json
import struct
import urllib.parse
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mesh_normal.files.errors import MeshFileError, failure_reason, unsupported

#: ``name -> bytes`` for a file next to the ``.gltf`` (its path as the URI gives it), or
#: ``None`` when there is none; ``None`` as a whole when the asset came alone.
Resolver = Callable[[str], bytes | None]

#: Required extensions we honour: these two change geometry and are decoded; the rest only
#: change how a surface looks (materials, textures, lights), which the normals never use.
HONOURED = frozenset(
    {
        "KHR_mesh_quantization",
        "KHR_draco_mesh_compression",
        "KHR_texture_transform",
        "KHR_texture_basisu",
        "EXT_texture_webp",
        "EXT_texture_avif",
        "KHR_lights_punctual",
        "KHR_materials_variants",
    }
)
_LOOKS_ONLY = "KHR_materials_"  # every KHR_materials_* extension

_GLB_MAGIC, _JSON_CHUNK, _BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942

#: Normalized integer component types and the divisor of the spec's decoding; signed ones
#: clamp at -1 (``max(c / 32767, -1)`` for int16), unsigned ones do not need to.
_NORMALIZED = {
    5120: ("<i1", 127.0),
    5121: ("<u1", 255.0),
    5122: ("<i2", 32767.0),
    5123: ("<u2", 65535.0),
}
#: Bytes of each glTF component type.
ITEM_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_FLOAT = 5126


def glb_parts(data: bytes) -> tuple[dict[str, Any], memoryview | None]:
    """The JSON header and the binary chunk (``None`` if absent) of a GLB file."""
    # ValueError, which read_mesh words as "could not be read as GLB: ..."
    if len(data) < 20:
        raise ValueError("it is truncated, with no complete header")
    magic, version, _length = struct.unpack_from("<III", data)
    if magic != _GLB_MAGIC:
        raise ValueError("it does not start with the GLB magic bytes")
    if version != 2:
        raise unsupported(f"This is GLB version {version}; only glTF 2.0 is supported.")
    chunks: dict[int, memoryview] = {}
    view = memoryview(data)  # the chunks as views: the binary one is most of the file
    offset = 12
    while offset + 8 <= len(data):
        size, kind = struct.unpack_from("<II", data, offset)
        if offset + 8 + size > len(data):
            raise ValueError("it is truncated: a chunk runs past its end")
        chunks.setdefault(kind, view[offset + 8 : offset + 8 + size])
        offset += 8 + size
    if _JSON_CHUNK not in chunks:
        raise ValueError("it has no JSON chunk")
    return _json(bytes(chunks[_JSON_CHUNK])), chunks.get(_BIN_CHUNK)


def gltf_header(data: bytes) -> dict[str, Any]:
    """The JSON of a ``.gltf`` file."""
    return _json(data)


def _json(data: bytes) -> dict[str, Any]:
    try:
        header = json.loads(data.decode("utf-8").rstrip("\0 "))
    except ValueError as error:  # not UTF-8, not JSON, or an integer of too many digits
        raise MeshFileError(
            f"The glTF JSON could not be parsed: {failure_reason(error)}."
        ) from error
    if not isinstance(header, dict):
        raise MeshFileError("The glTF JSON is not an object.")
    return header


def check_extensions(header: dict[str, Any]) -> None:
    """Refuse (415) a required extension we cannot honour, naming it."""
    required = [str(name) for name in header.get("extensionsRequired") or []]
    missing = [
        name for name in required if name not in HONOURED and not name.startswith(_LOOKS_ONLY)
    ]
    if missing:
        names = ", ".join(missing)
        raise unsupported(
            f"This glTF needs {names}, which {'is' if len(missing) == 1 else 'are'} not "
            "supported; export it without that compression or extension (Draco and "
            "KHR_mesh_quantization are read)."
        )
    used = set(required) | {str(name) for name in header.get("extensionsUsed") or []}
    # trimesh decodes Draco with DracoPy; without it, it would leave zeros
    if "KHR_draco_mesh_compression" in used and importlib.util.find_spec("DracoPy") is None:
        raise unsupported(
            "This glTF is Draco-compressed (KHR_draco_mesh_compression) and the DracoPy "
            "package, which decodes it, is not installed: pip install DracoPy."
        )


@dataclasses.dataclass(frozen=True, slots=True)
class Packed:
    """The glTF trimesh reads, and what was decoded on the way (for the notes).

    ``header`` names one buffer, :data:`PACKED_URI`, which is ``blob``: trimesh reads it
    through a resolver as a memoryview, so that its views and accessors are not copies.
    """

    header: bytes
    blob: bytearray
    quantized: int  # normalized integer accessors decoded
    draco: int  # Draco-compressed primitives decoded


#: The one buffer's name in a packed header.
PACKED_URI = "packed.bin"


def packed_gltf(
    header: dict[str, Any], glb_chunk: bytes | memoryview | None, resolve: Resolver | None
) -> Packed:
    """One glTF JSON and one buffer holding every buffer, Draco and quantized accessors
    decoded."""
    blob = bytearray()
    starts, lengths = [], []
    for index, buffer in enumerate(header.get("buffers") or []):
        starts.append(len(blob))
        blob += _buffer_bytes(index, buffer, glb_chunk, resolve)
        lengths.append(len(blob) - starts[-1])
        blob += b"\0" * (-len(blob) % 4)
    for index, view in enumerate(header.get("bufferViews") or []):
        buffer = view.get("buffer", 0)
        if not _is_size(buffer) or buffer >= len(starts):
            raise MeshFileError(f"The glTF buffer view {index} names a buffer that is missing.")
        _check_view(index, view, lengths[buffer])
        view["byteOffset"] = view.get("byteOffset", 0) + starts[buffer]
        view["buffer"] = 0
        view.pop("extensions", None)  # EXT_meshopt_compression's own buffers: we read fallbacks
    header["buffers"] = [{"byteLength": len(blob), "uri": PACKED_URI}] if blob else []
    _check_accessors(header)
    draco = _decode_draco(header, blob)
    quantized = _decode_normalized(header, blob)
    for key in ("images", "textures", "samplers"):  # never read: the geometry needs none
        header.pop(key, None)
    for material in header.get("materials") or []:
        material.clear()
    text = json.dumps(header, separators=(",", ":")).encode("utf-8")
    return Packed(text, blob, quantized, draco)


def _is_size(value: object) -> bool:
    """Whether a JSON value is a whole number, 0 or more (``true`` is not)."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _check_view(index: int, view: dict[str, Any], buffer_length: int) -> None:
    """Refuse a buffer view that does not fit its buffer (trimesh would assert)."""
    offset, length = view.get("byteOffset", 0), view.get("byteLength")
    if not _is_size(offset) or not _is_size(length) or offset + length > buffer_length:
        raise MeshFileError(
            f"The glTF buffer view {index} does not fit in its buffer of {buffer_length:,} bytes."
        )
    stride = view.get("byteStride")
    if stride is not None and (not _is_size(stride) or stride == 0):
        raise MeshFileError(f"The glTF buffer view {index} has a byteStride that is not above 0.")


def _check_accessors(header: dict[str, Any]) -> None:
    """Refuse an accessor that does not fit its buffer view or has no valid count, component
    type or type (trimesh would assert, or fail to reshape)."""
    views = header.get("bufferViews") or []
    for index, accessor in enumerate(header.get("accessors") or []):
        if not isinstance(accessor, dict):
            raise MeshFileError(f"The glTF accessor {index} is not an object.")
        kind, shape = accessor.get("componentType"), accessor.get("type")
        item = 0
        if isinstance(kind, int) and isinstance(shape, str):
            item = ITEM_BYTES.get(kind, 0) * WIDTH.get(shape, 0)
        if not _is_size(accessor.get("count")) or not item:
            raise MeshFileError(
                f"The glTF accessor {index} has no valid count, componentType or type."
            )
        if "bufferView" not in accessor:  # zeros, or filled by Draco
            continue
        view, offset = accessor["bufferView"], accessor.get("byteOffset", 0)
        if not _is_size(view) or view >= len(views) or not _is_size(offset):
            raise MeshFileError(f"The glTF accessor {index} names a buffer view that is missing.")
        stride = views[view].get("byteStride") or item
        count = accessor["count"]
        if count and offset + (count - 1) * stride + item > views[view]["byteLength"]:
            raise MeshFileError(
                f"The glTF accessor {index} runs past the end of its buffer view {view}."
            )


def _buffer_bytes(
    index: int,
    buffer: dict[str, Any],
    glb_chunk: bytes | memoryview | None,
    resolve: Resolver | None,
) -> bytes | memoryview:
    uri = buffer.get("uri")
    length = int(buffer.get("byteLength", 0))
    if uri is None:
        if index == 0 and glb_chunk is not None:
            return glb_chunk[:length]
        raise MeshFileError(f"The glTF buffer {index} has no data (no uri and no GLB chunk).")
    if uri.startswith("data:"):
        try:
            return base64.b64decode(uri.split(",", 1)[1], validate=False)[:length]
        except (IndexError, binascii.Error) as error:
            raise MeshFileError(f"The glTF buffer {index} has a broken data: URI.") from error
    found = resolve(urllib.parse.unquote(uri)) if resolve is not None else None
    if found is None:
        where = "is not in the .zip" if resolve is not None else "does not come with it"
        raise MeshFileError(
            f"The glTF file refers to the separate buffer file {uri[:100]}, which "
            f"{where}; send the .gltf with its files (together in one request, or in a .zip), "
            "or a .glb."
        )
    return found[:length]


def _decode_draco(header: dict[str, Any], blob: bytearray) -> int:
    """Decode every Draco primitive into plain accessors appended to ``blob``.

    Done here rather than by trimesh so that a Draco attribute holding quantized integers
    (``normalized`` with an integer type, as gltf-transform writes) is decoded like any other:
    DracoPy gives its integer values, which would be 32767 times too large as they are.
    """
    import DracoPy

    decoded = 0
    views, accessors = header.get("bufferViews") or [], header.get("accessors") or []
    for mesh in header.get("meshes") or []:
        for primitive in mesh.get("primitives") or []:
            extension = (primitive.get("extensions") or {}).pop("KHR_draco_mesh_compression", None)
            if extension is None:
                continue
            view = views[extension["bufferView"]]
            start = view.get("byteOffset", 0)
            try:
                draco = DracoPy.decode(bytes(blob[start : start + view["byteLength"]]))
            except MemoryError:  # the server's shortage, not a broken primitive
                raise
            except Exception as error:  # DracoPy's own failures, worded once
                raise MeshFileError(
                    f"A Draco-compressed glTF primitive is broken: {error}."
                ) from error
            ids = extension.get("attributes") or {}
            by_id = {attribute["unique_id"]: attribute["data"] for attribute in draco.attributes}
            attributes = {}
            for name in ("POSITION", "NORMAL"):
                if name in ids and ids[name] in by_id and name in primitive.get("attributes", {}):
                    target = accessors[primitive["attributes"][name]]
                    values = np.asarray(by_id[ids[name]], dtype=np.float32).reshape(-1, 3)
                    attributes[name] = _append(header, blob, values, 5126, target)
            if (
                "COLOR_0" in ids
                and ids["COLOR_0"] in by_id
                and "COLOR_0" in primitive.get("attributes", {})
            ):
                target = accessors[primitive["attributes"]["COLOR_0"]]
                values, component = _draco_colors(by_id[ids["COLOR_0"]], target)
                attributes["COLOR_0"] = _append(header, blob, values, component, None)
            primitive["attributes"] = attributes
            faces = getattr(draco, "faces", None)  # a point cloud has none
            if faces is None:
                primitive.pop("indices", None)
            else:
                indices = np.asarray(faces, dtype=np.uint32).reshape(-1)
                primitive["indices"] = _append(header, blob, indices, 5125, None)
            decoded += 1
    return decoded


#: glTF component types of colours, by NumPy type.
_COLOR_COMPONENTS = {"u1": 5121, "u2": 5123, "f4": 5126}


def _draco_colors(data: Any, accessor: dict[str, Any]) -> tuple[NDArray[Any], int]:
    """A Draco ``COLOR_0`` as its accessor declares it: bytes, shorts or float32 0-1."""
    kind = {5121: "u1", 5123: "u2"}.get(accessor.get("componentType", 5126), "f4")
    width = WIDTH.get(accessor.get("type", ""), 3)
    values = np.asarray(data)
    values = values.reshape(len(values), -1)[:, :width] if values.size else values.reshape(0, width)
    if kind == "f4" and values.dtype.kind in "ui":  # integers where floats are declared
        values = values / float(np.iinfo(values.dtype.str).max)
    return np.ascontiguousarray(values.astype(kind)), _COLOR_COMPONENTS[kind]


def _append(
    header: dict[str, Any],
    blob: bytearray,
    values: NDArray[Any],
    component: int,
    like: dict[str, Any] | None,
) -> int:
    """Append ``values`` as a new accessor (normalized as ``like`` says), giving its index."""
    if like is not None and like.get("normalized") and like.get("componentType") in _NORMALIZED:
        divisor = _NORMALIZED[like["componentType"]][1]
        values = np.maximum(values / divisor, -1.0).astype(np.float32)
    blob += b"\0" * (-len(blob) % 4)
    views = header.setdefault("bufferViews", [])
    views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": values.nbytes})
    blob += np.ascontiguousarray(values).tobytes()
    accessors = header.setdefault("accessors", [])
    kind = "SCALAR" if values.ndim == 1 else f"VEC{values.shape[1]}"
    accessors.append(
        {
            "bufferView": len(views) - 1,
            "componentType": component,
            "count": len(values),
            "type": kind,
        }
    )
    if header.get("buffers"):
        header["buffers"][0]["byteLength"] = len(blob)
    return len(accessors) - 1


def _decode_normalized(header: dict[str, Any], blob: bytearray) -> int:
    """Rewrite each normalized integer accessor as a float32 one appended to ``blob``."""
    decoded = 0
    views = header.get("bufferViews") or []
    colors = _color_only(header)
    for index, accessor in enumerate(header.get("accessors") or []):
        kind = accessor.get("componentType")
        if not accessor.get("normalized") or kind not in _NORMALIZED or index in colors:
            continue
        if "sparse" in accessor:
            raise unsupported("This glTF has a sparse normalized accessor, which is not supported.")
        if "bufferView" not in accessor:  # Draco fills it: its decoder gives floats
            continue
        index = accessor["bufferView"]
        if not isinstance(index, int) or not 0 <= index < len(views):
            raise MeshFileError(f"A glTF accessor names buffer view {index!r}, which is missing.")
        values = _dequantized(accessor, views[index], blob, kind)
        blob += b"\0" * (-len(blob) % 4)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": values.nbytes})
        blob += values.tobytes()
        accessor.update(bufferView=len(views) - 1, byteOffset=0, componentType=_FLOAT)
        for key in ("normalized", "min", "max"):
            accessor.pop(key, None)
        decoded += 1
    header["bufferViews"] = views
    if header.get("buffers"):
        header["buffers"][0]["byteLength"] = len(blob)
    return decoded


def _color_only(header: dict[str, Any]) -> set[int]:
    """Accessors of unsigned bytes or shorts that only ``COLOR_n`` attributes use: left as
    integers, which is how vertex colours are kept (0-255, 0-65535), never decoded to floats."""
    used: dict[bool, set[int]] = {True: set(), False: set()}
    for mesh in header.get("meshes") or []:
        for primitive in mesh.get("primitives") or []:
            for name, index in (primitive.get("attributes") or {}).items():
                used[str(name).startswith("COLOR_")].add(index)
            for target in primitive.get("targets") or []:
                used[False].update((target or {}).values())
    accessors = header.get("accessors") or []
    return {
        index
        for index in used[True] - used[False]
        if isinstance(index, int)
        and 0 <= index < len(accessors)
        and accessors[index].get("componentType") in (5121, 5123)
    }


def _dequantized(
    accessor: dict[str, Any], view: dict[str, Any], blob: bytearray, kind: int
) -> NDArray[np.float32]:
    """``(count, width) float32``: the accessor's integers decoded as the spec says."""
    dtype, divisor = _NORMALIZED[kind]
    item = np.dtype(dtype).itemsize
    count, width = int(accessor.get("count", 0)), WIDTH.get(accessor.get("type", ""), 1)
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    stride = view.get("byteStride") or item * width
    end = start + (count - 1) * stride + item * width if count else start
    if (
        count < 0
        or stride < item * width
        or end > view.get("byteOffset", 0) + view.get("byteLength", 0)
        or end > len(blob)
    ):
        raise MeshFileError("A glTF accessor runs past the end of its buffer view.")
    raw = np.frombuffer(blob, dtype=np.uint8, count=end - start, offset=start)
    rows = np.lib.stride_tricks.as_strided(raw, (count, item * width), (stride, 1))
    values = np.ascontiguousarray(rows).view(dtype).reshape(count, width) / divisor
    return np.maximum(values, -1.0).astype(np.float32)
