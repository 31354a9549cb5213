"""The hostile archives and 3MF packages of ``tests/data/hostile/``, made here.

``python -m tests.hostile_archives`` writes them again; the tests read the files, and one test
checks that they are still what these functions make (the zips' dates are fixed).
"""

from __future__ import annotations

import struct
import zipfile
from io import BytesIO

from tests.paths import DATA

HOSTILE = DATA / "hostile"
#: A fixed date for every member, so that the same content makes the same bytes.
DATE = (2024, 1, 1, 0, 0, 0)

NAMESPACE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
TYPES = (
    b'<?xml version="1.0" encoding="UTF-8"?>\n'
    b'<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    b'<Default Extension="model" '
    b'ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>'
)


def zipped(members: dict[str, bytes], method: int = zipfile.ZIP_DEFLATED) -> bytes:
    """A zip of ``members`` (in order), each dated :data:`DATE`."""
    buffer = BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, data in members.items():
            info = zipfile.ZipInfo(name, DATE)
            info.compress_type = method
            archive.writestr(info, data, compresslevel=9)
    return buffer.getvalue()


def package(model: bytes) -> bytes:
    """A 3MF package of the model part ``model`` (any bytes, any encoding)."""
    return zipped({"[Content_Types].xml": TYPES, "3D/3dmodel.model": model})


def zip64_claim(entries: int) -> bytes:
    """A zip whose end records (zip64) state ``entries`` members: a local header's start, an
    empty directory, and the zip64 end record, its locator and the end record."""
    head = b"PK\x03\x04" + bytes(26)
    end64 = struct.pack(
        "<4sQ2H2L4Q", b"PK\x06\x06", 44, 45, 45, 0, 0, entries, entries, 0, len(head)
    )
    locator = struct.pack("<4sLQL", b"PK\x06\x07", 0, len(head), 1)
    end = struct.pack("<4s4H2LH", b"PK\x05\x06", 0, 0, 0xFFFF, 0xFFFF, 0xFFFFFFFF, 0xFFFFFFFF, 0)
    return head + end64 + locator + end


def directory_of(entries: int, stated: int | None = None) -> bytes:
    """A zip whose directory holds ``entries`` records (empty stored files named by number,
    one local header they all point at), its end record stating ``stated`` (the count by
    default, as a 16-bit count wraps)."""
    local = struct.pack("<4s5H3L2H", b"PK\x03\x04", 20, 0, 0, 0, 0, 0, 0, 0, 1, 0) + b"0"
    records = b"".join(
        struct.pack("<4s6H3L5H2L", b"PK\x01\x02", 20, 20, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0)
        + b"0"
        for _ in range(entries)
    )
    count = (entries if stated is None else stated) & 0xFFFF
    end = struct.pack("<4s4H2LH", b"PK\x05\x06", 0, 0, count, count, len(records), len(local), 0)
    return local + records + end


def model_xml(resources: str, build: str) -> str:
    return (
        f'<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xmlns="{NAMESPACE}">'
        f"<resources>{resources}</resources><build>{build}</build></model>"
    )


def strip_object(triangles: int) -> str:
    """One object: a strip of ``triangles`` triangles."""
    columns = triangles // 2 + 1
    points = "".join(f'<vertex x="{i}" y="{j}" z="0"/>' for i in range(columns) for j in (0, 1))
    faces = "".join(
        f'<triangle v1="{2 * i}" v2="{2 * i + 2}" v3="{2 * i + 1}"/>'
        f'<triangle v1="{2 * i + 1}" v2="{2 * i + 2}" v3="{2 * i + 3}"/>'
        for i in range(triangles // 2)
    )
    return (
        f'<object id="1" type="model"><mesh><vertices>{points}</vertices>'
        f"<triangles>{faces}</triangles></mesh></object>"
    )


def encoded(text: str, encoding: str) -> bytes:
    """``text`` in ``encoding``, with the byte order mark of a UTF-16 one."""
    marks = {"utf-16-le": b"\xff\xfe", "utf-16-be": b"\xfe\xff"}
    return marks.get(encoding, b"") + text.encode(encoding)


def declaration(encoding: str) -> str:
    return f'<?xml version="1.0" encoding="{"UTF-16" if "16" in encoding else "UTF-8"}"?>\n'


def utf16_dtd(encoding: str = "utf-16") -> bytes:
    """A model part (UTF-16 with its byte order mark by default) that declares an entity and
    uses it."""
    text = (
        declaration(encoding) + '<!DOCTYPE model [<!ENTITY a "aaaaaaaaaaaaaaaa">]>'
        f'<model xmlns="{NAMESPACE}"><resources>&a;</resources><build/></model>'
    )
    return encoded(text, encoding)


def billion_laughs(encoding: str = "utf-16") -> bytes:
    """Ten levels of entities, each ten of the one below: 10**9 copies of "lol"."""
    entities = '<!ENTITY lol0 "lol">' + "".join(
        f'<!ENTITY lol{level} "{f"&lol{level - 1};" * 10}">' for level in range(1, 10)
    )
    text = (
        declaration(encoding) + f"<!DOCTYPE model [{entities}]>"
        f'<model xmlns="{NAMESPACE}"><resources>&lol9;</resources><build/></model>'
    )
    return encoded(text, encoding)


def placements(count: int = 2500, triangles: int = 2040) -> bytes:
    """A 3MF whose build places one object of ``triangles`` triangles ``count`` times."""
    build = '<item objectid="1"/>' * count
    return package(model_xml(strip_object(triangles), build).encode())


def threemf_in_zip(items: int = 2_000_000) -> bytes:
    """A .zip holding a 3MF whose model part is about 40 MB of build items (each 20 bytes
    of XML), deflated twice: a few kilobytes."""
    model = model_xml(strip_object(2), '<item objectid="1"/>' * items).encode()
    return zipped({"part.3mf": package(model)})


FILES = {
    "zip_many_entries.zip": lambda: zip64_claim(400_001),
    "3mf_utf16_dtd.3mf": lambda: package(utf16_dtd()),
    "3mf_billion_laughs_utf16.3mf": lambda: package(billion_laughs()),
    "3mf_in_zip.zip": threemf_in_zip,
    "3mf_2500_placements.3mf": placements,
}


if __name__ == "__main__":
    HOSTILE.mkdir(exist_ok=True)
    for name, make in FILES.items():
        (HOSTILE / name).write_bytes(make())
        print(name, len(make()))
