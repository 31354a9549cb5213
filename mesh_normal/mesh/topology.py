"""How the faces of a triangle mesh hang together: edges, patches, components, corners.

Terms. Half-edge ``3 * f + k`` runs from ``faces[f, k]`` to ``faces[f, (k + 1) % 3]``. An
edge is an unordered pair of vertices, *used* by every face that has it as a half-edge. A
corner is one vertex of one face, numbered ``3 * face + k`` for ``faces[face, k]``, so corner
ids follow ``faces.ravel()`` (see :func:`vertex_corners`).

By position. Files often give each piece of an object its own vertices (a cube whose six
sides are separate patches, a head with separate eyes). Given a mesh (a
:class:`~mesh_normal.mesh.checks.CheckedMesh` or its geometry), the topology therefore looks at
*points*: vertices with identical coordinates (exact equality, -0.0 equal to 0.0) are one
point, represented by the first of them (:func:`same_points`), and "vertex" below means
point. An optional weld tolerance, a fraction of the bounding-box diagonal, also joins
vertices that miss each other by rounding; it is off by default. Every output still names
the file's vertices (a point by its first vertex) and keeps the faces in their order; given
raw faces without coordinates, :func:`mesh_topology` can only go by index.

- A face with a repeated vertex (``[4, 4, 7]``, or two corners at one point) has no edges
  here: it is left out of every count and of all adjacency, belongs to no component
  (label -1) and is never flipped. A face with three distinct points counts, even if they
  are collinear.
- A *boundary* edge is used by exactly one face, a *non-manifold* edge by three or more.
  A mesh is *watertight* when it has at least one face and neither kind of edge.
- A *component* is a set of faces connected through shared edges, non-manifold ones too.
  Isolated vertices are in no component. Duplicate faces are faces like any other (two
  copies of a face on a closed mesh make its edges non-manifold).
- Winding is *consistent* when the two faces of every manifold edge (used by exactly two
  faces) traverse it in opposite directions. Non-manifold edges count neither for nor against
  it, and orientation is not carried across them: they are reported, not judged.
- A *patch* is a set of faces connected through manifold edges; a component is several
  patches only where non-manifold edges split it. A patch is *orientable* when flipping some
  of its faces can make its winding consistent; a Moebius strip is not.

Speed. One integer sort of the 3m half-edges groups them by edge, and a union-find with
parities (one loop of the compiled core, :mod:`mesh_normal._core`; path compression, the
smaller root wins) labels the patches in nearly O(m) work.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

import mesh_normal._core as _core
from mesh_normal.mesh.checks import (
    MESH_FORMS,
    CheckedMesh,
    HeldMesh,
    check_faces,
    held_mesh,
    read_only,
)
from mesh_normal.mesh.faces import FaceGeometry
from mesh_normal.types import BoolArray, FloatArray, IndexArray, ParityArray

#: Sort keys (edge * 3m + half-edge, vertex * 3m + corner) must stay below this to fit int64
#: with room to spare.
KEY_LIMIT = 2**62


@dataclass(frozen=True, slots=True)
class MeshTopology:
    """Edges, components and winding of a mesh (see the module docstring for the terms).

    Attributes
    ----------
    boundary_edges : int
        Edges used by exactly one face.
    nonmanifold_edges : int
        Edges used by three or more faces.
    components : int
        Edge-connected components.
    face_component : (m,) intp
        The component of each face, numbered 0 .. components - 1 in order of their first
        face; -1 for a face with a repeated index.
    watertight : bool
        At least one face, and no boundary or non-manifold edge.
    winding_consistent : bool
        Every manifold edge is traversed in opposite directions by its two faces (true when
        there is no manifold edge).
    orientable : bool
        Every patch can be made consistent by flipping faces.
    boundary_edge_list : (b, 2) intp
        The boundary edges, each in the direction its face traverses it, sorted by their
        smaller vertex, then the larger.
    nonmanifold_edge_list : (k, 2) intp
        The non-manifold edges, each as (smaller vertex, larger vertex), sorted.
    """

    boundary_edges: int
    nonmanifold_edges: int
    components: int
    face_component: IndexArray
    watertight: bool
    winding_consistent: bool
    orientable: bool
    boundary_edge_list: IndexArray
    nonmanifold_edge_list: IndexArray


@dataclass(frozen=True, slots=True)
class Structure:
    """What mesh_topology and orient need: the topology and the patches with their parities."""

    topology: MeshTopology
    group: IndexArray  # (m,) patch of each face; faces with a repeated point get ``patches``
    patches: int
    parity: ParityArray  # (m,) 1 where a face must flip to agree with its patch's first face
    orientable: BoolArray  # (patches,)
    patch_component: IndexArray  # (patches,)
    closed: BoolArray  # (components,)


def mesh_topology(
    faces: ArrayLike | HeldMesh | FaceGeometry,
    vertex_count: int | None = None,
    *,
    weld: float | None = None,
) -> MeshTopology:
    """Count the boundary and non-manifold edges and the components; judge the winding.

    Parameters
    ----------
    faces : (m, 3) int, a mesh or FaceGeometry
        Indices into ``vertex_count`` vertices; or a mesh as
        :func:`~mesh_normal.mesh.checks.checked_mesh` takes it (read_mesh's, a
        ``(vertices, faces)`` tuple, trimesh, Open3D, PyVista) or its geometry, then without
        ``vertex_count``. A mesh is judged by position (vertices with identical
        coordinates are one point); raw faces, having no coordinates, by index.
    vertex_count : int
        n, the number of vertices.
    weld : float, optional
        With a mesh: also join vertices closer than this fraction of the bounding-box
        diagonal (see :func:`same_points`). Off by default.

    Returns
    -------
    MeshTopology
        See the module docstring for the terms.

    Examples
    --------
    >>> t = mesh_topology([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], 4)
    >>> t.watertight, t.winding_consistent, t.components
    (True, True, 1)
    """
    if isinstance(faces, FaceGeometry):
        faces = faces.mesh
    if vertex_count is None and not isinstance(faces, CheckedMesh | np.ndarray | list):
        faces = held_mesh(faces)
    if isinstance(faces, CheckedMesh):
        if vertex_count is not None:
            raise TypeError("a checked mesh holds its vertex count: pass it alone.")
        return structure(by_position(faces, weld), len(faces.vertices)).topology
    if vertex_count is None:
        raise TypeError(
            "vertex_count is required with raw faces: pass faces and vertex_count, or a mesh "
            f"alone ({MESH_FORMS})."
        )
    if weld is not None:
        raise TypeError("welding needs the coordinates: pass a mesh.")
    # With a vertex count, ``faces`` is the raw index array (check_faces refuses anything else).
    indices = check_faces(faces, vertex_count)  # type: ignore[arg-type]
    return structure(indices, vertex_count).topology


def by_position(mesh: CheckedMesh, weld: float | None = None) -> IndexArray:
    """(m, 3) intp: the faces with each vertex replaced by the first at its position."""
    if mesh.distinct_points and not weld:  # a welded STL's vertices are its points already
        return mesh.faces
    point = same_points(mesh.vertices, weld)
    return mesh.faces if point is None else point[mesh.faces]


# --- edges, patches and components -----------------------------------------------------------


def structure(
    faces: IndexArray, vertex_count: int, on_open: Callable[[], object] | None = None
) -> Structure:
    """The edges, patches and components of ``faces`` (by position) over ``vertex_count``
    points; ``on_open`` is called as soon as a boundary edge is known (the mesh is open), so
    that what only an open mesh needs can start ahead (``orientation.HeadStart``)."""
    faces = np.ascontiguousarray(faces, dtype=np.intp)  # as the compiled kernels take them
    valid = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2])
    valid &= faces[:, 2] != faces[:, 0]
    key, face, forward = _sorted_half_edges(faces, valid, vertex_count)
    # The runs of equal keys: edges used once (boundary), twice (paired: their positions in 4
    # bytes where they fit) and more (non-manifold: their first position and how many use
    # it), found in one compiled walk with nothing kept a half-edge.
    counts = _core.count_runs(key)
    if counts[0] and on_open is not None:  # a boundary edge: what an open mesh needs, ahead
        on_open()
    boundary, nonmanifold, uses = (np.empty(counts[i], dtype=np.intp) for i in (0, 2, 2))
    paired: NDArray[np.int32] | IndexArray = (
        np.empty(counts[1], dtype=np.int32)
        if len(key) < 2**31
        else np.empty(counts[1], dtype=np.intp)
    )
    _core.find_runs(key, boundary, paired, nonmanifold, uses)
    boundary_edge_list = _edge_list(key[boundary], forward[boundary], vertex_count)
    nonmanifold_edge_list = _edge_list(key[nonmanifold], None, vertex_count)
    del key
    # The two faces of each manifold edge, and whether they run along it the same way.
    one, two = np.empty(len(paired), dtype=face.dtype), np.empty(len(paired), dtype=face.dtype)
    same = np.empty(len(paired), dtype=np.int8)
    _core.pair_faces(face, forward, paired, one, two, same)
    del paired, forward
    root, parity = _connected(len(faces), one, two, same)
    patch, firsts = _numbered(root, valid)
    del root
    patches = len(firsts)
    orientable = np.ones(patches, dtype=bool)
    _core.mark_unorientable(one, two, same, parity, patch, orientable)
    del one, two
    face_component, components = _merged(patch, patches, face, nonmanifold, uses)
    closed = np.ones(components, dtype=bool)
    closed[face_component[face[np.r_[boundary, nonmanifold]]]] = False
    topology = MeshTopology(
        boundary_edges=len(boundary),
        nonmanifold_edges=len(nonmanifold),
        components=components,
        face_component=face_component,
        watertight=components > 0 and bool(closed.all()),
        winding_consistent=not same.any(),
        orientable=bool(orientable.all()),
        boundary_edge_list=boundary_edge_list,
        nonmanifold_edge_list=nonmanifold_edge_list,
    )
    # Every face valid (the common case): the groups are the patches, not a copy of them.
    group = read_only(patch) if valid.all() else np.where(valid, patch, patches)
    return Structure(topology, group, patches, parity, orientable, face_component[firsts], closed)


def _edge_list(key: IndexArray, forward: NDArray[np.int8] | None, vertex_count: int) -> IndexArray:
    """(k, 2) vertex pairs of edge keys, smaller vertex first unless ``forward`` is 0."""
    edges = np.stack(np.divmod(key, max(vertex_count, 1)), axis=1)
    if forward is not None:
        edges[forward == 0] = edges[forward == 0, ::-1]
    return edges


def _sorted_half_edges(
    faces: IndexArray, valid: BoolArray, vertex_count: int
) -> tuple[IndexArray, IndexArray, NDArray[np.int8]]:
    """The half-edges of valid faces sorted by edge, then by face.

    Returns the edge key min * n + max, the face, and 1 where the face runs along the edge
    from min to max, of each. Sorting unique values key * 2**s + 2 * face + forward is several
    times faster than an argsort (NumPy sorts integers with SIMD), and the face and direction
    come out of it without a gather; past ``KEY_LIMIT`` two stable sorts of positions, by
    max and then by min, do it.
    """
    bits = len(faces).bit_length() + 1
    if vertex_count * vertex_count << bits < KEY_LIMIT:
        # Packed in one pass, straight into the array that is sorted: 8 bytes a half-edge
        # (NumPy's minimum, maximum and shifts held three (m, 3) int64 arrays at once).
        # A counting sort by the smaller vertex, the key's leading part, then a sort of each
        # vertex's few half-edges (about six on a closed surface): the same values in the same
        # order as sorting the whole array, in two passes over it (about four times faster).
        packed = np.empty(3 * int(np.count_nonzero(valid)), dtype=np.int64)
        _core.sorted_half_edges(faces, valid, vertex_count, bits, packed)
        direction = np.empty(len(packed), dtype=np.int8)  # a byte, not eight, for a 0 or 1
        if bits <= 32 and sys.byteorder == "little":
            # The face and direction are in the low 32 bits: read them there, 4 bytes a face.
            low_word = packed.view(np.uint32)[::2]
            np.bitwise_and(low_word, 1, out=direction, casting="unsafe")
            faces_word = low_word >> 1
            faces_word &= (1 << bits - 1) - 1  # the key's lowest bits are above the face's
            face_of: IndexArray = faces_word.view(np.int32)
        else:
            np.bitwise_and(packed, 1, out=direction, casting="unsafe")
            face_of = packed >> 1
            face_of &= (1 << bits - 1) - 1
        packed >>= bits
        return packed, face_of, direction
    if vertex_count * vertex_count < KEY_LIMIT and vertex_count << bits < KEY_LIMIT:
        return _wide_half_edges(faces, valid, vertex_count)
    following = faces[:, [1, 2, 0]]
    low, high = np.minimum(faces, following), np.maximum(faces, following)
    forward = (faces < following).view(np.int8)
    del following
    face = np.arange(len(faces))[:, None]
    if not valid.all():
        low, high, forward, face = low[valid], high[valid], forward[valid], face[valid]
    face = np.broadcast_to(face, low.shape)
    low, high, face, forward = (np.ravel(array) for array in (low, high, face, forward))
    bits = len(low).bit_length()
    if vertex_count << bits < KEY_LIMIT:
        position = np.arange(len(low))
        mask = (1 << bits) - 1
        by_high = np.sort(high << bits | position) & mask
        by_both = by_high[np.sort(low[by_high] << bits | position) & mask]
    else:
        by_both = np.lexsort((high, low))
    return low[by_both] * vertex_count + high[by_both], face[by_both], forward[by_both]


def _wide_half_edges(
    faces: IndexArray, valid: BoolArray, vertex_count: int
) -> tuple[IndexArray, IndexArray, NDArray[np.int8]]:
    """:func:`_sorted_half_edges` where the edge key fits int64 but not with the face beside
    it (the Lucy size: 7M points): the same arrays in the same order, from a counting sort by
    the smaller vertex and a sort of each vertex's few by the larger, instead of two full sorts
    of positions (about ten times faster at the Lucy size)."""
    count = 3 * int(np.count_nonzero(valid))
    key = np.empty(count, dtype=np.int64)
    face: IndexArray = np.empty(count, dtype=np.int32 if len(faces) < 2**31 else np.intp)
    forward = np.empty(count, dtype=np.int8)
    bits = len(faces).bit_length() + 1
    _core.wide_half_edges(faces, valid, vertex_count, bits, key, face, forward)
    return key, face, forward


def _connected(
    count: int, one: IndexArray, two: IndexArray, same: IndexArray | ParityArray
) -> tuple[IndexArray, ParityArray]:
    """Label the nodes of a graph with the smallest node connected to them.

    Nodes ``one[i]`` and ``two[i]`` are joined, with parity ``same[i]`` (1 when exactly one
    of them must flip to agree with the other). Returns each node's label and its parity
    relative to the labelling node; where a cycle has odd parity (not orientable) the
    parities conflict and are meaningless, but the labels are right regardless.
    """
    root = np.empty(count, dtype=np.intp)
    parity = np.empty(count, dtype=np.int8)  # 0 or 1: one byte a face
    # The edges' nodes in 4 bytes (as the half-edge sort gives them) for every graph of fewer
    # than 2**31 nodes, the parities in one. Edges in order, so the labels and parities are
    # the same on any number of threads.
    node = np.int32 if count < 2**31 else np.intp
    _core.union_find(
        count,
        np.ascontiguousarray(one, dtype=node),
        np.ascontiguousarray(two, dtype=node),
        np.ascontiguousarray(same, dtype=np.int8),
        root,
        parity,
    )
    return root, parity


def _merged(
    patch: IndexArray,
    patches: int,
    face: IndexArray,
    nonmanifold: IndexArray,
    uses: IndexArray,
) -> tuple[IndexArray, int]:
    """Join the patches around each non-manifold edge (its first sorted position and how many
    half-edges use it) into components; number them."""
    if not len(nonmanifold):
        return patch, patches
    # Link each later half-edge of a non-manifold edge to the edge's first half-edge.
    group = np.repeat(nonmanifold, uses)
    position = group + np.arange(len(group)) - np.repeat(np.cumsum(uses) - uses, uses)
    one, two = patch[face[group]], patch[face[position]]
    root, _ = _connected(patches, one, two, np.zeros(len(one), dtype=np.intp))
    number, firsts = _numbered(root, np.ones(patches, dtype=bool))
    return np.where(patch >= 0, number[patch], -1), len(firsts)


def _numbered(root: IndexArray, valid: BoolArray) -> tuple[IndexArray, IndexArray]:
    """Number the roots 0, 1, ... in order; -1 for invalid nodes. Also returns the roots.

    ``root`` (each node's smallest connected node, as :func:`_connected` labels them) is
    overwritten with the numbers: one array a face instead of four at once.
    """
    firsts = _core.number_roots(root, valid)
    return root, firsts


# --- corners around vertices ------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class VertexCorners:
    """The corners of every vertex, as one sorted array and offsets into it.

    Attributes
    ----------
    order : (3 m,) intp
        Corner ids sorted by vertex, and by corner id within a vertex.
    starts : (n + 1,) intp
        The corners of vertex ``v`` are ``order[starts[v]:starts[v + 1]]``.
    """

    order: IndexArray
    starts: IndexArray

    @property
    def counts(self) -> IndexArray:
        """(n,) intp: how many corners (face uses) each vertex has."""
        return np.diff(self.starts)


def vertex_corners(
    faces: IndexArray, vertex_count: int, corners: IndexArray | None = None
) -> VertexCorners:
    """Group the corners of ``faces`` (or just the given ``corners``) by vertex.

    Parameters
    ----------
    faces : (m, 3) intp
        Checked indices (see :func:`mesh_normal.mesh.checks.check_mesh`).
    vertex_count : int
        n, the number of vertices.
    corners : (k,) intp, optional
        Corner ids to group, in increasing order; all 3 m corners by default.

    Returns
    -------
    VertexCorners
        A stable sort of the corner ids by vertex, and the offsets of each vertex's group
        (empty groups for vertices with no corner among those given).
    """
    flat = faces.ravel()
    ids = np.arange(len(flat)) if corners is None else corners
    vertex = flat[ids]
    span = len(flat)
    if vertex_count * span < KEY_LIMIT:
        # Sorting unique keys vertex * span + corner is stable by construction and several
        # times faster than a stable argsort (NumPy sorts integer values with SIMD).
        order = np.sort(vertex * span + ids) % span
    else:
        order = ids[np.argsort(vertex, kind="stable")]
    starts = np.zeros(vertex_count + 1, dtype=np.intp)
    np.cumsum(np.bincount(vertex, minlength=vertex_count), out=starts[1:])
    return VertexCorners(order, starts)


# --- the same point: vertices with identical coordinates ----------------------------------------


def same_points(vertices: FloatArray, weld: float | None = None) -> IndexArray | None:
    """Map each vertex to the first vertex at the same position; None when all differ.

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates.
    weld : float, optional
        Also join vertices closer than ``weld`` times the diagonal of the bounding box in
        every coordinate (see :func:`_welded`); off (exact equality only) by default.

    Returns
    -------
    (n,) intp or None
        ``point[v]`` is the smallest vertex at ``v``'s position (joined transitively when
        welding); None stands for the identity, the common case, found with one sort.
    """
    if weld is not None and not (math.isfinite(weld) and weld >= 0):
        raise ValueError(f"The weld tolerance must be a finite number >= 0, not {weld!r}.")
    point = _identical(vertices)
    if not weld or len(vertices) < 2:
        return point
    return _welded(vertices, weld, point)


_HASH_FACTORS = (
    np.uint64(0x9E3779B97F4A7C15),
    np.uint64(0xC2B2AE3D27D4EB4F),
    np.uint64(0x165667B19E3779F9),
)


def _identical(rows: FloatArray) -> IndexArray | None:
    """The first row equal to each row (-0.0 equals 0.0), or None when all rows differ."""
    if len(rows) < 2:
        return None
    rows = rows + 0.0  # -0.0 becomes 0.0, so that equal numbers have equal bits
    bits = rows.view(np.uint64)
    # A hash of the bits: sorting one uint64 key is a fraction of the cost of a row lexsort.
    key = row_hashes(bits)
    ordered = np.sort(key)
    if not (ordered[1:] == ordered[:-1]).any():
        return None
    order = np.argsort(key)
    same_key = ordered[1:] == ordered[:-1]
    same_row = same_key & _same_as_previous(bits[order])
    if (same_key != same_row).any():  # a hash collision: sort the rows themselves
        order = np.lexsort((rows[:, 2], rows[:, 1], rows[:, 0]))
        same_row = _same_as_previous(bits[order])
    if not same_row.any():
        return None
    # Each run of equal rows is represented by its smallest vertex.
    starts = np.flatnonzero(np.r_[True, ~same_row])
    point = np.empty(len(rows), dtype=np.intp)
    point[order] = np.repeat(np.minimum.reduceat(order, starts), np.diff(np.r_[starts, len(order)]))
    return point


def row_hashes(bits: np.ndarray) -> np.ndarray:
    """(k,) uint64: one hash of each row of (k, 3) uint64 words (the bits of a double each).

    A product's bits depend only on its factor's bits below them, and a double holds most of
    its information in its high bits (exponent, leading mantissa): so each word is folded
    first, its high half onto its low one. Multiplied unfolded, whole numbers (a weld's grid
    cells) and the vertices of a subdivided sphere would share keys by the hundred thousand
    and fall back to the lexsort, ten times slower.
    """
    key = np.zeros(len(bits), dtype=np.uint64)
    for column, factor in enumerate(_HASH_FACTORS):
        word = bits[:, column] >> np.uint64(32)
        word ^= bits[:, column]
        word *= factor
        key ^= word
    return key


def _same_as_previous(bits: np.ndarray) -> BoolArray:
    """(k - 1,) bool: whether each row of (k, 3) uint64 bits equals the one before it."""
    same: BoolArray = bits[1:, 0] == bits[:-1, 0]
    same &= bits[1:, 1] == bits[:-1, 1]
    same &= bits[1:, 2] == bits[:-1, 2]
    return same


def _welded(vertices: FloatArray, weld: float, point: IndexArray | None) -> IndexArray:
    """Join vertices that share a cell of side ``s = weld * diagonal`` in one of 8 grids.

    The grids are offset by 0 or s / 2 along each axis: two vertices closer than s / 2 in
    every coordinate share a cell in at least one of them (along each axis at most one of
    the two sets of cell walls, s / 2 apart, passes between them), and vertices that share a
    cell are closer than s in every coordinate. Joins are transitive (a chain of close
    vertices becomes one point), as in every welding tool.
    """
    low = vertices.min(axis=0)
    side = weld_distance(vertices, weld)
    count = len(vertices)
    identity = np.arange(count)
    one, two = [identity], [identity if point is None else point]
    with np.errstate(over="ignore", invalid="ignore"):
        relative = (vertices - low) / side if 0 < side < math.inf else np.empty((0, 3))
    # A side so small that the cells overflow (a subnormal weld), or one beyond the double
    # range, joins nothing beyond equality.
    if 0 < side < math.inf and np.isfinite(relative).all():
        for offset in np.ndindex(2, 2, 2):
            cells = np.floor(relative + 0.5 * np.array(offset, dtype=np.float64))
            same = _identical(cells)
            if same is not None:
                one.append(identity)
                two.append(same)
    first, second = np.concatenate(one), np.concatenate(two)
    root, _ = _connected(count, first, second, np.zeros(len(first), dtype=np.intp))
    return root


def weld_distance(vertices: FloatArray, weld: float) -> float:
    """The weld tolerance as a distance: ``weld`` times the bounding-box diagonal.

    Taken in halves and scaled, so that it is finite whenever the product is (a mesh from
    -1e308 to 1e308 has a finite box, though its extent overflows); 0.0 without vertices.
    """
    if not len(vertices):
        return 0.0
    half = vertices.max(axis=0) / 2 - vertices.min(axis=0) / 2
    scale = float(half.max())
    if scale == 0:
        return 0.0
    return 2 * weld * scale * float(np.linalg.norm(half / scale))  # inf beyond the range
