"""files.expansion: one budget an input for everything it expands into."""

from __future__ import annotations

import contextvars
import threading

import pytest

from mesh_normal.files import MeshFileError, expansion, read_mesh, read_mesh_files
from tests import hostile_archives as hostile
from tests.meshes import CUBE_OBJ


def test_the_limit_is_a_ratio_of_the_size_between_a_least_and_a_most() -> None:
    assert expansion.expansion_limit(1) == expansion.MIN_EXPANSION
    assert expansion.expansion_limit(10 * 2**20) == 1000 * 2**20
    assert expansion.expansion_limit(2**40) == expansion.MAX_EXPANSION
    assert expansion.expansion_limit(10 * 2**20, most=300 * 2**20) == 300 * 2**20


def test_set_most_sets_the_most_of_its_context_alone() -> None:
    def limited() -> int:
        expansion.set_most(512 * 2**20)
        return expansion.expansion_limit(2**30)

    assert contextvars.copy_context().run(limited) == 512 * 2**20
    assert expansion.expansion_limit(2**30) == expansion.MAX_EXPANSION


def test_a_charge_past_the_limit_is_a_413_naming_what_expanded() -> None:
    with expansion.expanding(22 * 2**10) as budget:
        expansion.charge(200 * 2**20, "the first part")
        with pytest.raises(expansion.ExpansionTooLarge) as error:
            expansion.charge(100 * 2**20, "the 3MF file's build, placing 400,000 triangles,")
    assert isinstance(error.value, MeshFileError) and error.value.status_code == 413
    assert str(error.value) == (
        "The upload of 22 KB expands too far: the 3MF file's build, placing 400,000 "
        "triangles, would take about 300 MB of memory, more than the 256 MB an upload of its "
        "size may expand into here (100 times its size, at least 256 MB)."
    )
    assert budget.used == 200 * 2**20  # what was refused is not taken


def test_outside_a_budget_a_charge_costs_nothing() -> None:
    expansion.charge(2**50, "anything")


def test_nested_budgets_are_the_outer_one() -> None:
    with expansion.expanding(100) as outer:
        with expansion.expanding(10**9) as inner:
            assert inner is outer
            expansion.charge(5, "a member")
        expansion.charge(7, "another")
    assert outer.used == 12


def test_threads_started_with_the_context_charge_the_same_budget() -> None:
    with expansion.expanding(100) as budget:
        context = contextvars.copy_context()
        thread = threading.Thread(target=context.run, args=(expansion.charge, 9, "a block"))
        thread.start()
        thread.join()
    assert budget.used == 9


def test_the_readers_open_a_budget_of_their_input() -> None:
    """read_mesh and read_mesh_files open one budget each; inside a caller's, they use it."""
    placements = hostile.placements()
    for read in (
        lambda: read_mesh(placements, "p.3mf"),
        lambda: read_mesh_files([("p.3mf", placements), ("notes.txt", b"")]),
    ):
        with pytest.raises(expansion.ExpansionTooLarge):
            read()
    small = hostile.placements(count=2, triangles=10)
    with expansion.expanding(1, most=10**9) as budget:
        read_mesh(CUBE_OBJ.encode(), "cube.obj")  # an OBJ expands into nothing
        assert budget.used == 0
        read_mesh_files([("p.3mf", small), ("notes.txt", b"")])
    assert budget.used > 20 * 250  # the 3MF's parts and build, charged to the caller's


@pytest.mark.parametrize(
    ("count", "words"),
    [(0, "0 KB"), (22 * 2**10, "22 KB"), (1.3 * 2**20, "1.3 MB"), (1260 * 2**20, "1,260 MB")],
)
def test_megabytes_in_words(count: float, words: str) -> None:
    assert expansion.megabytes(count) == words


def test_a_limit_set_by_the_most_says_so_and_a_close_call_is_just_over() -> None:
    with (
        expansion.expanding(10 * 2**20, most=300 * 2**20),
        pytest.raises(expansion.ExpansionTooLarge) as error,
    ):
        expansion.charge(300 * 2**20 + 1, "unpacking the .zip file's members")
    assert str(error.value).endswith(
        "would take just over 300 MB of memory, more than the 300 MB an upload of its size may "
        "expand into here (the most for one upload on this server)."
    )
