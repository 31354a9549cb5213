"""3MF packages built here: objects, build transforms, components, and broken packages."""

from __future__ import annotations

import io
import time
import zipfile

import numpy as np
import pytest
from fastapi.testclient import TestClient

from mesh_normal.files import MeshFileError, expansion, read_mesh, threemf
from mesh_normal.files.formats import ACCEPTED_SUFFIXES, FORMATS
from mesh_normal.files.read import sniff
from tests import hostile_archives as hostile
from tests.conftest import assert_error
from tests.paths import DATA

TETRA_VERTICES = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
#: Counter-clockwise seen from outside, as 3MF asks.
TETRA_TRIANGLES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package'
    '.relationships+xml"/><Default Extension="model" '
    'ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>'
)
RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Target="/3D/{part}" Id="rel0" '
    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>'
)
#: Row vectors times this: (x, y, z) -> (-y, x, z), a quarter turn about z.
TURN = "0 1 0 -1 0 0 0 0 1 0 0 0"


def mesh_object(
    number: int, vertices: list[tuple[float, ...]], triangles: list[tuple[int, ...]]
) -> str:
    points = "".join(f'<vertex x="{x}" y="{y}" z="{z}"/>' for x, y, z in vertices)
    faces = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in triangles)
    return (
        f'<object id="{number}" type="model"><mesh><vertices>{points}</vertices>'
        f"<triangles>{faces}</triangles></mesh></object>"
    )


def model(resources: str, build: str) -> str:
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xml:lang="en-US" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">'
        f"<resources>{resources}</resources><build>{build}</build></model>"
    )


def package(model_xml: str | None, part: str = "3dmodel.model", rels: bool = True) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("[Content_Types].xml", TYPES)
        if rels:
            archive.writestr("_rels/.rels", RELS.format(part=part))
        if model_xml is not None:
            archive.writestr(f"3D/{part}", model_xml)
    return buffer.getvalue()


def tetrahedron() -> bytes:
    return package(model(mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES), '<item objectid="1"/>'))


def test_the_format_table_has_3mf() -> None:
    entry = FORMATS["3mf"]
    assert (entry.suffixes, entry.media_type, entry.writable) == ((".3mf",), "model/3mf", False)
    assert ".3mf" in ACCEPTED_SUFFIXES


def test_a_tetrahedron() -> None:
    data = tetrahedron()
    assert sniff(data) == "3mf"
    mesh = read_mesh(data)  # no name: told from the bytes, not a generic .zip
    assert mesh.format == "3mf" and mesh.source_faces == 4 and mesh.notes == ()
    np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)
    np.testing.assert_array_equal(mesh.faces, TETRA_TRIANGLES)


def test_two_objects_with_build_transforms_keep_file_order() -> None:
    second = [(0, 0, 0), (2, 0, 0), (0, 2, 0)]
    resources = mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES) + mesh_object(
        7, second, [(0, 1, 2)]
    )
    build = (
        '<item objectid="1" transform="1 0 0 0 1 0 0 0 1 10 0 0"/>'
        f'<item objectid="7" transform="{TURN}"/>'
    )
    mesh = read_mesh(package(model(resources, build)), "two.3mf")
    assert (len(mesh.vertices), len(mesh.faces)) == (7, 5)
    np.testing.assert_array_equal(mesh.vertices[:4], np.add(TETRA_VERTICES, (10, 0, 0)))
    np.testing.assert_allclose(mesh.vertices[4:], [(0, 0, 0), (0, 2, 0), (-2, 0, 0)])
    np.testing.assert_array_equal(mesh.faces, [*TETRA_TRIANGLES, (4, 5, 6)])
    assert mesh.notes == ("Joined 2 3MF meshes from 2 build items, with their transforms applied.",)


def test_each_build_item_is_a_group() -> None:
    resources = mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES) + (
        '<object id="2" type="model"><components>'
        '<component objectid="1" transform="1 0 0 0 1 0 0 0 1 5 0 0"/>'
        '<component objectid="1" transform="1 0 0 0 1 0 0 0 1 9 0 0"/></components></object>'
        '<object id="3" type="model"><components></components></object>'
    )
    build = '<item objectid="3"/><item objectid="2"/><item objectid="1"/>'
    mesh = read_mesh(package(model(resources, build)), "items.3mf")
    # The empty item makes no triangle and no group; the item of two components is one.
    assert mesh.group_names == ("build item 2 (object 2)", "build item 3 (object 1)")
    assert mesh.face_groups is not None
    np.testing.assert_array_equal(mesh.face_groups, [0] * 8 + [1] * 4)


def test_components_compose_with_the_item_transform() -> None:
    resources = mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES) + (
        '<object id="2" type="model"><components>'
        '<component objectid="1" transform="1 0 0 0 1 0 0 0 1 1 0 0"/>'
        '<component objectid="1"/></components></object>'
    )
    mesh = read_mesh(package(model(resources, f'<item objectid="2" transform="{TURN}"/>')))
    assert len(mesh.vertices) == 8 and len(mesh.faces) == 8
    # translated first (the component), then turned (the item): (0, 0, 0) -> (1, 0, 0) -> (0, 1, 0)
    np.testing.assert_allclose(mesh.vertices[0], (0, 1, 0), atol=1e-12)
    np.testing.assert_allclose(mesh.vertices[4:], [(0, 0, 0), (0, 1, 0), (-1, 0, 0), (0, 0, 1)])


def test_a_mirroring_transform_reverses_the_winding() -> None:
    resources = mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES)
    item = '<item objectid="1" transform="-1 0 0 0 1 0 0 0 1 0 0 0"/>'
    mesh = read_mesh(package(model(resources, item)))
    np.testing.assert_array_equal(mesh.faces, np.array(TETRA_TRIANGLES)[:, ::-1])
    np.testing.assert_array_equal(mesh.vertices[1], (-1, 0, 0))
    assert "Reversed the winding of 1 mirrored" in mesh.notes[0]


def test_the_model_part_the_relationships_name() -> None:
    resources = mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES)
    data = package(model(resources, '<item objectid="1"/>'), part="other.model")
    assert sniff(data) == "3mf"  # by its content types, not by the usual part name
    assert len(read_mesh(data).faces) == 4


def test_a_3mf_inside_a_zip() -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("parts/tetra.3mf", tetrahedron())
    mesh = read_mesh(buffer.getvalue(), "parts.zip")
    assert mesh.format == "3mf" and mesh.notes == ("Read parts/tetra.3mf from the .zip file.",)


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (package(None), "has no model part (3D/3dmodel.model)"),
        (package("<model><resources>", rels=False), "XML is broken"),
        (
            package(model(mesh_object(1, TETRA_VERTICES, [(0, 1, 4)]), '<item objectid="1"/>')),
            "Triangle 0 (counting from 0) of object 1 refers to vertex 4, but the object has 4",
        ),
        (
            package(model(mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES), '<item objectid="9"/>')),
            "refers to object '9', which it lacks",
        ),
        (package(model(mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES), "")), "names no objects"),
        (
            package(
                model(
                    '<object id="1"><components><component objectid="1"/></components></object>',
                    '<item objectid="1"/>',
                )
            ),
            "nests components deeper",
        ),
        (
            package(
                model(
                    mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES),
                    '<item objectid="1" transform="1 0 0"/>',
                )
            ),
            "transform that is not 12 numbers",
        ),
        (
            package(
                model(
                    '<object id="1"><mesh><vertices><vertex x="1" y="a" z="0"/>'
                    "</vertices></mesh></object>",
                    '<item objectid="1"/>',
                )
            ),
            "vertex 0 (counting from 0) of object 1 has a missing or non-numeric x/y/z",
        ),
        (
            package('<!DOCTYPE m [<!ENTITY a "aaaa">]><model>&a;</model>'),
            "declares a DTD",
        ),
    ],
)
def test_broken_packages_are_one_sentence(data: bytes, words: str) -> None:
    with pytest.raises(MeshFileError) as error:
        read_mesh(data, "broken.3mf")
    assert error.value.status_code == 400 and words in str(error.value)
    assert str(error.value).endswith(".") and str(error.value).count(". ") == 0


def test_a_zip_named_3mf_without_a_model_is_not_read_as_a_zip() -> None:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("readme.txt", "hi")
    with pytest.raises(MeshFileError, match="no model part"):
        read_mesh(buffer.getvalue(), "empty.3mf")


def test_upload_a_3mf(client: TestClient) -> None:
    response = client.post("/api/mesh", files={"file": ("tetra.3mf", tetrahedron())})
    assert response.status_code == 200, response.text
    report = response.json()
    assert report["file"]["format"] == "3mf" and report["faces"] == 4
    assert report["orientation"] == "outward"


def test_upload_a_broken_3mf(client: TestClient) -> None:
    response = client.post("/api/mesh", files={"file": ("bad.3mf", package(None))})
    assert_error(response, 400, "file", "3MF", "no model part")


def test_components_in_other_model_parts_are_a_415() -> None:
    resources = (
        '<object id="1" xmlns:p="http://schemas.microsoft.com/3dmanufacturing/production/2015/06">'
        '<components><component objectid="1" p:path="/3D/part.model"/></components></object>'
    )
    with pytest.raises(MeshFileError, match="production extension") as error:
        read_mesh(package(model(resources, '<item objectid="1"/>')))
    assert error.value.status_code == 415


def test_the_parts_unpack_into_the_budget_of_the_input() -> None:
    resources = mesh_object(1, TETRA_VERTICES * 20_000, TETRA_TRIANGLES)  # compresses well
    data = package(model(resources, '<item objectid="1"/>'))
    with (
        expansion.expanding(len(data), most=2 * 2**20),
        pytest.raises(
            expansion.ExpansionTooLarge, match=r"unpacking 3D/3dmodel\.model from the 3MF"
        ),
    ):
        read_mesh(data, "bomb.3mf")


def test_a_3mf_inside_a_zip_charges_the_same_budget() -> None:
    inner = tetrahedron()
    with zipfile.ZipFile(io.BytesIO(inner)) as source:
        xml = len(source.read("3D/3dmodel.model"))
    outer = hostile.zipped({"parts/tetra.3mf": inner})
    with expansion.expanding(len(outer)) as budget:
        read_mesh(outer, "parts.zip")
    # the 3MF's bytes, its model part's, their parse, and the build: one budget for all
    assert budget.used >= len(inner) + xml * (1 + threemf.XML_PER_BYTE) + 4 * 250


@pytest.mark.parametrize("encoding", ["utf-8", "utf-16", "utf-16-le", "utf-16-be"])
def test_a_dtd_is_refused_in_any_encoding(encoding: str) -> None:
    for xml in (hostile.utf16_dtd(encoding), hostile.billion_laughs(encoding)):
        started = time.perf_counter()
        with pytest.raises(MeshFileError) as error:
            read_mesh(hostile.package(xml), "dtd.3mf")
        assert time.perf_counter() - started < 5
        assert error.value.status_code == 400
        assert str(error.value) == (
            "The 3MF file's XML declares a DTD (or entities), which this reader refuses."
        )


@pytest.mark.parametrize(
    ("name", "status", "words"),
    [
        ("3mf_utf16_dtd.3mf", 400, "The 3MF file's XML declares a DTD (or entities)"),
        ("3mf_billion_laughs_utf16.3mf", 400, "The 3MF file's XML declares a DTD (or entities)"),
        ("3mf_in_zip.zip", 413, "the 3MF file's XML elements would take"),
        (
            "3mf_2500_placements.3mf",
            413,
            "the 3MF file's build, placing 5,100,000 triangles and 5,105,000 vertices, would",
        ),
    ],
)
def test_the_hostile_packages(name: str, status: int, words: str) -> None:
    started = time.perf_counter()
    with pytest.raises(MeshFileError) as error:
        read_mesh(hostile.HOSTILE / name)
    assert time.perf_counter() - started < 30  # seconds, not the minutes an unguarded read takes
    assert error.value.status_code == status and words in str(error.value)
    assert str(error.value).endswith(".") and ". " not in str(error.value)


def test_the_hostile_files_are_what_their_makers_make() -> None:
    for name, make in hostile.FILES.items():
        assert (hostile.HOSTILE / name).read_bytes() == make(), name


def test_an_encoding_expat_lacks_is_one_sentence() -> None:
    xml = '<?xml version="1.0" encoding="UTF-16-LE"?><model/>'.encode("utf-16-le")
    with pytest.raises(MeshFileError) as error:
        read_mesh(hostile.package(b"\xff\xfe" + xml), "odd.3mf")
    assert str(error.value) == "The 3MF file's XML is in an encoding this reader does not support."


def test_placements_within_the_budget_are_read() -> None:
    data = hostile.placements(count=20, triangles=100)
    with expansion.expanding(len(data)) as budget:
        mesh = read_mesh(data, "twenty.3mf")
    assert len(mesh.faces) == 2000 and len(mesh.vertices) == 20 * 102
    assert budget.used >= 2000 * threemf.PLACED_TRIANGLE_BYTES


def test_the_elements_the_parse_keeps_are_charged() -> None:
    build = '<item objectid="1"/>' * 10_000
    data = package(model(mesh_object(1, TETRA_VERTICES, TETRA_TRIANGLES), build))
    with expansion.expanding(len(data)) as budget:
        assert len(read_mesh(data, "items.3mf").faces) == 40_000
    assert budget.used >= 8192 * threemf.KEPT_BYTES


def test_a_zip_listing_too_many_members_is_no_3mf_and_is_refused_as_one() -> None:
    data = hostile.zip64_claim(400_001)
    assert sniff(data) is None
    with pytest.raises(MeshFileError, match="The 3MF file lists 400,001 members") as error:
        read_mesh(data, "many.3mf")
    assert error.value.status_code == 413


@pytest.mark.parametrize("leaf", [TETRA_TRIANGLES[:1], []])
def test_components_that_double_at_every_level_are_refused_before_placing(
    leaf: list[tuple[int, ...]],
) -> None:
    # Each object places the one below it twice: 2**32 placements from a few kilobytes. The
    # count comes first (per object, once), so this is refused at once, empty leaves included.
    levels = [mesh_object(0, TETRA_VERTICES, leaf)]
    levels += [
        f'<object id="{i}" type="model"><components>'
        + f'<component objectid="{i - 1}"/>' * 2
        + "</components></object>"
        for i in range(1, 33)
    ]
    data = package(model("".join(levels), '<item objectid="32"/>'))
    with pytest.raises(MeshFileError, match="makes more than 50,000,000 triangles"):
        read_mesh(data, "bomb.3mf")


MATERIALS = 'xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02"'
COLOURS = (
    '<basematerials id="5"><base name="red" displaycolor="#FF0000"/>'
    '<base name="clear" displaycolor="#00FF0080"/></basematerials>'
    '<m:colorgroup id="6"><m:color color="#0000FFFF"/><m:color color="#102030"/></m:colorgroup>'
)


def coloured(triangles: list[str], object_colour: str = 'pid="5" pindex="1"') -> bytes:
    """The tetrahedron with colour resources, a default colour on the object and attributes
    on each triangle."""
    points = "".join(f'<vertex x="{x}" y="{y}" z="{z}"/>' for x, y, z in TETRA_VERTICES)
    faces = "".join(
        f'<triangle v1="{a}" v2="{b}" v3="{c}" {extra}/>'
        for (a, b, c), extra in zip(TETRA_TRIANGLES, triangles, strict=True)
    )
    obj = (
        f'<object id="1" type="model" {object_colour}><mesh><vertices>{points}</vertices>'
        f"<triangles>{faces}</triangles></mesh></object>"
    )
    xml = model(COLOURS + obj, '<item objectid="1"/>').replace("<model ", f"<model {MATERIALS} ")
    return package(xml)


def test_triangle_colours_from_colour_groups_and_base_materials() -> None:
    data = coloured(['pid="6" p1="0"', "", 'pid="6" p1="1"', 'pid="5" p1="0"'])
    mesh = read_mesh(data, "c.3mf")
    assert mesh.face_colors is not None and mesh.face_colors.dtype == np.uint8
    assert mesh.face_colors.tolist() == [
        [0, 0, 255, 255],
        [0, 255, 0, 128],  # the object's default: base 1 of group 5
        [16, 32, 48, 255],  # #RRGGBB is opaque
        [255, 0, 0, 255],
    ]
    assert mesh.notes == ()


def test_a_colour_per_corner_keeps_the_first_corners() -> None:
    mesh = read_mesh(coloured(['pid="6" p1="0" p2="1" p3="1"', "", "", ""]), "c.3mf")
    assert mesh.face_colors is not None
    assert mesh.face_colors[0].tolist() == [0, 0, 255, 255]
    assert mesh.notes == (
        "1 3MF triangles have a colour per corner; each keeps its first corner's as its "
        "face colour.",
    )


def test_colours_on_only_some_triangles_are_not_kept_and_say_so() -> None:
    mesh = read_mesh(coloured(['pid="6" p1="0"', "", "", ""], object_colour=""), "c.3mf")
    assert mesh.face_colors is None
    assert mesh.notes[0].startswith("The 3MF colours were not kept: 3 of 4 triangles have no")


def test_no_colours_no_note() -> None:
    mesh = read_mesh(coloured(["", "", "", ""], object_colour=""), "c.3mf")
    assert mesh.face_colors is None and mesh.notes == ()


@pytest.mark.parametrize(
    ("triangle", "words"),
    [
        ('pid="6" p1="2"', "names colour '2' of group '6', which has 2"),
        ('pid="6" p1="x"', "names colour 'x'"),
        ('pid="6" p1="-1"', "names colour '-1'"),
    ],
)
def test_colour_indices_out_of_range_are_one_sentence(triangle: str, words: str) -> None:
    with pytest.raises(MeshFileError, match=words) as error:
        read_mesh(coloured([triangle, "", "", ""]), "c.3mf")
    assert str(error.value).startswith("Triangle 0 (counting from 0) of object 1")


def test_a_colour_that_is_not_hex_is_one_sentence_where_used() -> None:
    with zipfile.ZipFile(io.BytesIO(coloured(['pid="6" p1="1"', "", "", ""]))) as source:
        xml = source.read("3D/3dmodel.model").replace(b"#102030", b"blue").decode()
    with pytest.raises(MeshFileError, match=r"not #RRGGBB\[AA\]: 'blue'"):
        read_mesh(package(xml), "c.3mf")
    unused = xml.replace('pid="6" p1="1"', "")  # a broken colour nobody uses breaks nothing
    assert read_mesh(package(unused), "c.3mf").face_colors is not None


def test_a_real_file_with_base_materials() -> None:
    """trimesh's models/featuretype.3MF: the object's pid and pindex name its one material."""
    data = (DATA / "threemf_basematerials.3mf").read_bytes()
    mesh = read_mesh(data, "featuretype.3mf")
    assert mesh.face_colors is not None and mesh.face_colors.shape == (2208, 4)
    assert np.unique(mesh.face_colors, axis=0).tolist() == [[0xCA, 0xD1, 0xEE, 0]]
