"""Thousands of broken files made from real ones: bytes changed, files cut short, header counts
inflated. Each is read and reported in full (every kernel of the compiled core runs on what a
reader accepted), and each either gives a report or is refused with one sentence: no crash, no
other exception, nothing read out of bounds (``make test-sanitize`` runs this file under
AddressSanitizer and UndefinedBehaviorSanitizer)."""

from __future__ import annotations

import random
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

import mesh_normal as mn
from mesh_normal.files import MeshFileError

DATA = Path(__file__).resolve().parents[2] / "data"

#: Real files of every mesh format, small enough to report many times over.
MESHES = [
    "ant.ply",
    "colors_blender.ply",
    "colors_meshlab.ply",
    "cube.obj",
    "cube_compressed.obj",
    "fuze.obj",
    "multibody.stl",
    "nut.ply",
    "off_face_colors.off",
    "off_whitespace.off",
    "soup.stl",
    "sphere.ply",
    "teapot.stl",
    "threemf_basematerials.3mf",
    "two_objects.obj",
    "two_objects_mixed_case_names.stl",
    "gltf/BoxMeshopt.glb",
    "gltf/cube_vertex_colors.glb",
    "gltf/DenseSphere.glb",
]
CLOUDS = ["points/colored_cloud.pcd", "points/pcl_logo.pcd"]
#: Mutations of each file.
EACH = 120

#: Numbers a header might be made to say.
INFLATED = [b"0", b"1", b"4294967295", b"4294967296", b"9223372036854775807", b"-1", b"99999999"]
_NUMBER = re.compile(rb"\d+")


def mutations(data: bytes, seed: int) -> Iterator[tuple[str, bytes]]:
    """``EACH`` broken copies of ``data``, the same ones every run, each with what was done."""
    rng = random.Random(seed)
    head = data[: min(len(data), 2048)]
    numbers = list(_NUMBER.finditer(head))
    for index in range(EACH):
        kind = index % 4
        if kind == 0:  # a few bytes changed anywhere
            changed = bytearray(data)
            for _ in range(rng.randint(1, 8)):
                changed[rng.randrange(len(changed))] = rng.randrange(256)
            yield f"bytes changed ({index})", bytes(changed)
        elif kind == 1:  # cut short
            cut = rng.randrange(len(data))
            yield f"cut at byte {cut}", data[:cut]
        elif kind == 2 and numbers:  # a number in the header (a count, a length) inflated
            found = rng.choice(numbers)
            value = rng.choice(INFLATED)
            yield (
                f"header number at byte {found.start()} set to {value.decode()}",
                data[: found.start()] + value + data[found.end() :],
            )
        else:  # four bytes of a binary count or offset (or of text) set to a large word
            changed = bytearray(data)
            at = rng.randrange(max(1, min(len(changed) - 4, 256)))
            changed[at : at + 4] = rng.choice(
                [b"\xff\xff\xff\xff", b"\xff\xff\xff\x7f", b"\0\0\0\x80"]
            )
            yield f"word at byte {at} inflated", bytes(changed)


def assert_refused(error: MeshFileError, what: str) -> None:
    assert_one_sentence(str(error), what)
    assert error.status_code in (400, 413, 415), (what, error.status_code)


def assert_one_sentence(message: str, what: str) -> None:
    assert message and "\n" not in message and len(message) < 600, (what, message)
    assert "Traceback" not in message and "Error" not in message, (what, message)


@pytest.mark.parametrize("name", MESHES)
def test_mutated_meshes_are_reported_or_refused_in_one_sentence(name: str) -> None:
    data = (DATA / name).read_bytes()
    filename = Path(name).name
    reported = refused = 0
    for what, mutated in mutations(data, seed=len(data)):
        try:
            report = mn.analyse(mutated, filename)
        except MeshFileError as error:
            assert_refused(error, what)
            refused += 1
        else:
            assert report.to_json(), what
            reported += 1
    assert reported + refused == EACH
    assert refused > 0  # cut-short copies at least


@pytest.mark.parametrize("name", CLOUDS)
def test_mutated_point_clouds_are_estimated_or_refused_in_one_sentence(name: str) -> None:
    data = (DATA / name).read_bytes()
    filename = Path(name).name
    refused = 0
    for what, mutated in mutations(data, seed=len(data)):
        try:
            cloud = mn.read_points(mutated, filename)
            normals = mn.point_normals(cloud.points, k=8)
        except MeshFileError as error:
            assert_one_sentence(str(error), what)
            refused += 1
        except ValueError as error:  # a cloud the estimate refuses (too few points)
            assert_one_sentence(str(error), what)
            refused += 1
        else:
            assert len(normals.normals) == len(cloud.points), what
    assert refused > 0
