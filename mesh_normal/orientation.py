"""How a triangle mesh hangs together, and which way its faces point.

Terms. Half-edge ``3 * f + k`` runs from ``faces[f, k]`` to ``faces[f, (k + 1) % 3]``. An
edge is an unordered pair of vertices, *used* by every face that has it as a half-edge.

- A face with a repeated index (``[4, 4, 7]``) has no edges here: it is left out of every
  count and of all adjacency, belongs to no component (label -1) and is never flipped.
  A face with three distinct indices counts, even if its points are collinear or coincide.
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

Which way is out. :func:`orient` first makes each orientable patch consistent, then takes the
sign of V = sum of det(A - c, B - c, C - c) / 6 over its faces, where c is the patch's
area-weighted centroid. For a closed patch V is the enclosed volume whatever c is, positive
when the faces point outward (method ``"volume"``). For an open patch it is the heuristic
(method ``"heuristic"``): the signed volume of the cone from the centroid over the faces,
positive when the faces, weighted by area and distance, face away from the centroid. For a
bowl, an open box or a hemisphere that is the convex, outer side: the side Blender's
"Recalculate Outside" picks. Blender looks only at the face farthest from the centre; this sum
does not hinge on one face, and it is the volume itself when the patch happens to be closed.

When |V| is at most ``MESH_FLAT_SINE`` times sum |det| / 6 (what V would be if every face faced
away from c), the patch is *flat*: a plane sheet, or a closed surface that encloses nothing
(two faces back to back). Its direction is undetermined; :func:`orient` still makes it
consistent, keeping the winding of the majority of its faces (of its lowest-numbered face on
a tie). A non-orientable patch is left as it is.

Speed. One integer sort of the 3m half-edges groups them by edge, and a union-find with
parities (one loop compiled with numba, like the kernels of :mod:`mesh_normal.faces`; path
compression, the smaller root wins) labels the patches in nearly O(m) work. :func:`orient`
returns the topology too, so a caller that needs both calls only :func:`orient`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Literal, overload

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from mesh_normal.faces import check_faces, check_mesh, scaling
from mesh_normal.tolerances import MESH_FLAT_SINE

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]
Verdict = Literal["outward", "inward", "mixed", "undetermined"]
Method = Literal["volume", "heuristic", "none"]

VERDICTS: tuple[Verdict, ...] = ("outward", "inward", "mixed", "undetermined")
METHODS: tuple[Method, ...] = ("volume", "heuristic", "none")


#: Sort keys edge * 3m + half-edge must stay below this to fit int64 with room to spare.
KEY_LIMIT = 2**62

_OUTWARD, _INWARD, _MIXED, _UNDETERMINED = range(4)
_VOLUME, _HEURISTIC, _NONE = range(3)


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
class ComponentOrientation:
    """What :func:`orient` found and did in one component.

    Attributes
    ----------
    index : int
        The component's number, as in :attr:`MeshTopology.face_component`.
    faces : int
        How many faces it has.
    closed : bool
        It has no boundary or non-manifold edge.
    orientable : bool
        Every patch of it is orientable.
    method : {"volume", "heuristic", "none"}
        How its outside was chosen: by the sign of its volume (closed and orientable), by the
        cone heuristic (open; at least one patch decided), or not at all (non-orientable,
        flat, or a closed surface enclosing no volume).
    flipped : int
        How many of its faces :func:`orient` reversed.
    volume : float or None
        Its signed volume after orienting, when closed and orientable; else None.
    orientation : {"outward", "inward", "mixed", "undetermined"}
        Its verdict as given (see :attr:`Orientation.orientation`).
    """

    index: int
    faces: int
    closed: bool
    orientable: bool
    method: Method
    flipped: int
    volume: float | None
    orientation: Verdict


@dataclass(frozen=True, slots=True, eq=False)
class ComponentTable(Sequence[ComponentOrientation]):
    """One :class:`ComponentOrientation` per component, stored as arrays.

    A triangle soup has as many components as faces, so the records are built only when
    indexed or iterated; the arrays serve vectorised use.

    Attributes
    ----------
    faces : (c,) intp
    closed : (c,) bool
    orientable : (c,) bool
    method : (c,) intp
        Indices into ``METHODS``.
    flipped : (c,) intp
    volume : (c,) float64
        Zero where ``has_volume`` is false.
    has_volume : (c,) bool
    orientation : (c,) intp
        Indices into ``VERDICTS``.
    """

    faces: IndexArray
    closed: BoolArray
    orientable: BoolArray
    method: IndexArray
    flipped: IndexArray
    volume: FloatArray
    has_volume: BoolArray
    orientation: IndexArray

    def __len__(self) -> int:
        return len(self.faces)

    @overload
    def __getitem__(self, index: int) -> ComponentOrientation: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[ComponentOrientation, ...]: ...

    def __getitem__(
        self, index: int | slice
    ) -> ComponentOrientation | tuple[ComponentOrientation, ...]:
        if isinstance(index, slice):
            return tuple(self[i] for i in range(*index.indices(len(self))))
        i = range(len(self))[index]  # IndexError and negative indices, as for a tuple
        return ComponentOrientation(
            index=i,
            faces=int(self.faces[i]),
            closed=bool(self.closed[i]),
            orientable=bool(self.orientable[i]),
            method=METHODS[self.method[i]],
            flipped=int(self.flipped[i]),
            volume=float(self.volume[i]) if self.has_volume[i] else None,
            orientation=VERDICTS[self.orientation[i]],
        )

    def __iter__(self) -> Iterator[ComponentOrientation]:
        return (self[i] for i in range(len(self)))


@dataclass(frozen=True, slots=True)
class Orientation:
    """The result of :func:`orient`.

    Attributes
    ----------
    faces : (m, 3) intp
        The input faces, rows ``[a, b, c]`` that were flipped as ``[a, c, b]``.
    flipped : (m,) bool
        Which faces were reversed.
    orientation : {"outward", "inward", "mixed", "undetermined"}
        The verdict on the input. Each patch votes: "outward" if orient flipped none of its
        faces, "inward" if it flipped all, "mixed" if some; a flat patch votes "mixed" if its
        winding was inconsistent and not at all otherwise, a non-orientable one not at all.
        The verdict is the common vote, "mixed" if the votes differ, and "undetermined" if
        nothing voted (no faces; only flat or non-orientable parts).
    components : ComponentTable
        Per component, a sequence of :class:`ComponentOrientation`.
    volume : float or None
        The signed volume of the input (see :func:`signed_volume`) when it is watertight and
        consistently wound; else None.
    topology : MeshTopology
        The topology of the input, as :func:`mesh_topology` returns it.
    """

    faces: IndexArray
    flipped: BoolArray
    orientation: Verdict
    components: ComponentTable
    volume: float | None
    topology: MeshTopology


@dataclass(frozen=True, slots=True)
class _Structure:
    """What both public functions need: the topology and the patches with their parities."""

    topology: MeshTopology
    group: IndexArray  # (m,) patch of each face; faces with a repeated index get ``patches``
    patches: int
    parity: IndexArray  # (m,) 1 where a face must flip to agree with its patch's first face
    orientable: BoolArray  # (patches,)
    patch_component: IndexArray  # (patches,)
    closed: BoolArray  # (components,)


def mesh_topology(faces: ArrayLike, vertex_count: int) -> MeshTopology:
    """Count the boundary and non-manifold edges and the components; judge the winding.

    Parameters
    ----------
    faces : (m, 3) int
        Indices into ``vertex_count`` vertices.
    vertex_count : int
        n, the number of vertices.

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
    return _structure(check_faces(faces, vertex_count), vertex_count).topology


def signed_volume(vertices: ArrayLike, faces: ArrayLike) -> float:
    """Return the sum of det(A - c, B - c, C - c) / 6 over the faces.

    For a closed mesh this is the enclosed volume whatever c is, positive when the faces point
    outward. Here c is the area-weighted centroid of the faces, which keeps the terms small;
    for an open mesh the value is the volume of the cone from c (see the module docstring).

    Precision. Each term is computed as n . (A - c) with n = (B - A) x (C - A), after scaling
    the vertices by a power of two, within about 8 eps |n| |A - c| of its exact value
    (eps = 2**-53); the terms are summed pairwise. The result is within about
    (8 + log2 m) eps sum |n| |A - c| / 6 of the exact volume about c. It is infinite only
    beyond the double range (coordinates beyond about 1e102).

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates.
    faces : (m, 3) int
        Indices into ``vertices``.

    Returns
    -------
    float
        The signed volume; 0.0 for no faces.

    Examples
    --------
    >>> signed_volume([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    ...               [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    0.16666666666666666
    """
    points, indices = check_mesh(vertices, faces)
    if not len(indices):
        return 0.0
    terms, _, scale = _cone_terms(points, indices, np.zeros(len(indices), dtype=np.intp), 1)
    return _unscaled(float(np.sum(terms)) / 6, scale)


def orient(vertices: ArrayLike, faces: ArrayLike) -> Orientation:
    """Make the winding consistent and outward, patch by patch, and report what changed.

    Parameters
    ----------
    vertices : (n, 3) float64
        Finite coordinates; they are not changed.
    faces : (m, 3) int
        Indices into ``vertices``.

    Returns
    -------
    Orientation
        The oriented faces, which were flipped, the verdicts and the input's topology.

    Examples
    --------
    >>> inward = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]
    >>> r = orient([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], inward)
    >>> r.orientation, r.flipped.tolist(), r.components[0].volume
    ('inward', [True, True, True, True], 0.16666666666666666)
    """
    points, indices = check_mesh(vertices, faces)
    structure = _structure(indices, len(points))
    topology, group, parity = structure.topology, structure.group, structure.parity
    bins = structure.patches + 1  # the last for faces with a repeated index

    def per_patch(weights: FloatArray | IndexArray | None = None) -> FloatArray:
        return np.bincount(group, weights, bins)[:-1]

    terms, bounds, scale = _cone_terms(points, indices, group, bins)
    # The volume of each patch with its winding made consistent, its first face unchanged.
    volume = per_patch(np.where(parity, -terms, terms)) / 6
    size, against = per_patch(), per_patch(parity)
    orientable = structure.orientable
    decided = orientable & (np.abs(volume) > MESH_FLAT_SINE * per_patch(bounds) / 6)
    # Turn the consistent patch over when it points in, or when most of its faces are against
    # its first face (flat patches).
    turn = np.where(decided, volume < 0, 2 * against > size)
    flips = np.where(orientable, np.where(turn, size - against, against), 0).astype(np.intp)
    flipped = (parity ^ np.r_[turn, False][group]).astype(bool)
    flipped &= np.r_[orientable, False][group]
    vote = np.where(flips == 0, _OUTWARD, np.where(flips == size, _INWARD, _MIXED))
    vote[~decided] = np.where(flips[~decided] > 0, _MIXED, _UNDETERMINED)
    vote[~orientable] = _UNDETERMINED
    after = _unscaled_array(np.where(turn, -volume, volume), scale)
    components = _component_table(structure, decided, vote, flips, size, after)
    oriented = indices.copy()
    oriented[flipped, 1:] = indices[flipped, :0:-1]
    input_volume = None
    if topology.watertight and topology.winding_consistent:
        input_volume = _unscaled(float(np.sum(terms)) / 6, scale)
    return Orientation(
        oriented, flipped, VERDICTS[_combined(vote)], components, input_volume, topology
    )


# --- edges, patches and components -----------------------------------------------------------


def _structure(faces: IndexArray, vertex_count: int) -> _Structure:
    valid = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2])
    valid &= faces[:, 2] != faces[:, 0]
    key, face, forward = _sorted_half_edges(faces, valid, vertex_count)
    # At each sorted position: is the edge the same as the previous one, the next, the one
    # after next? Edges used once, twice and more follow.
    same_as_next = key[1:] == key[:-1]
    before, after, after_next = (np.zeros(len(key), dtype=bool) for _ in range(3))
    before[1:] = after[:-1] = same_as_next
    after_next[:-1] = after[1:]
    starting = ~before
    boundary = np.flatnonzero(starting & ~after)
    paired = np.flatnonzero(starting & after & ~after_next)
    nonmanifold = np.flatnonzero(starting & after & after_next)
    # The two faces of each manifold edge, and whether they run along it the same way.
    one, two = face[paired], face[paired + 1]
    same = forward[paired] == forward[paired + 1]
    root, parity = _connected(len(faces), one, two, same)
    patch, firsts = _numbered(root, valid)
    patches = len(firsts)
    orientable = np.ones(patches, dtype=bool)
    orientable[patch[one[(parity[one] ^ parity[two]) != same]]] = False
    face_component, components = _merged(patch, patches, face, starting, nonmanifold)
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
        boundary_edge_list=_edge_list(key[boundary], forward[boundary], vertex_count),
        nonmanifold_edge_list=_edge_list(key[nonmanifold], None, vertex_count),
    )
    group = np.where(valid, patch, patches)
    return _Structure(topology, group, patches, parity, orientable, face_component[firsts], closed)


def _edge_list(key: IndexArray, forward: IndexArray | None, vertex_count: int) -> IndexArray:
    """(k, 2) vertex pairs of edge keys, smaller vertex first unless ``forward`` is 0."""
    edges = np.stack(np.divmod(key, max(vertex_count, 1)), axis=1)
    if forward is not None:
        edges[forward == 0] = edges[forward == 0, ::-1]
    return edges


def _sorted_half_edges(
    faces: IndexArray, valid: BoolArray, vertex_count: int
) -> tuple[IndexArray, IndexArray, IndexArray]:
    """The half-edges of valid faces sorted by edge, then by face.

    Returns the edge key min * n + max, the face, and 1 where the face runs along the edge
    from min to max, of each. Sorting unique values key * 2**s + 2 * face + forward is several
    times faster than an argsort (NumPy sorts integers with SIMD), and the face and direction
    come out of it without a gather; past ``KEY_LIMIT`` two stable sorts of positions, by
    max and then by min, do it.
    """
    following = faces[:, [1, 2, 0]]
    low, high = np.minimum(faces, following), np.maximum(faces, following)
    forward = (faces < following).view(np.int8)
    face = np.arange(len(faces))[:, None]
    if not valid.all():
        low, high, forward, face = low[valid], high[valid], forward[valid], face[valid]
    bits = len(faces).bit_length() + 1
    if vertex_count * vertex_count << bits < KEY_LIMIT:
        packed = low * vertex_count
        packed += high
        packed <<= bits
        packed |= face << 1
        packed |= forward
        packed = packed.ravel()
        packed.sort()
        return packed >> bits, (packed >> 1) & ((1 << bits - 1) - 1), packed & 1
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


def _connected(
    count: int, one: IndexArray, two: IndexArray, same: IndexArray
) -> tuple[IndexArray, IndexArray]:
    """Label the nodes of a graph with the smallest node connected to them.

    Nodes ``one[i]`` and ``two[i]`` are joined, with parity ``same[i]`` (1 when exactly one
    of them must flip to agree with the other). Returns each node's label and its parity
    relative to the labelling node; where a cycle has odd parity (not orientable) the
    parities conflict and are meaningless, but the labels are right regardless.
    """
    root = np.empty(count, dtype=np.intp)
    parity = np.empty(count, dtype=np.intp)
    _union_find(
        count,
        np.ascontiguousarray(one, dtype=np.intp),
        np.ascontiguousarray(two, dtype=np.intp),
        np.ascontiguousarray(same, dtype=np.intp),
        root,
        parity,
    )
    return root, parity


@njit(cache=True)
def _find(parent: IndexArray, relation: IndexArray, node: int) -> tuple[int, int]:
    """The root of ``node`` and its parity to it; compresses the path on the way."""
    top, parity = node, 0
    while parent[top] != top:
        parity ^= relation[top]
        top = parent[top]
    step, step_parity = node, parity
    while parent[step] != step:
        following, following_parity = parent[step], step_parity ^ relation[step]
        parent[step], relation[step] = top, step_parity
        step, step_parity = following, following_parity
    return top, parity


@njit(cache=True)
def _union_find(
    count: int,
    one: IndexArray,
    two: IndexArray,
    same: IndexArray,
    root: IndexArray,
    parity: IndexArray,
) -> None:
    """Union-find with parities, one pass over the edges; the smaller root always wins."""
    parent = np.arange(count)
    relation = np.zeros(count, dtype=np.intp)
    for edge in range(len(one)):
        a, a_parity = _find(parent, relation, one[edge])
        b, b_parity = _find(parent, relation, two[edge])
        if a == b:
            continue
        low, high = (a, b) if a < b else (b, a)
        parent[high] = low
        relation[high] = a_parity ^ b_parity ^ same[edge]
    for node in range(count):
        root[node], parity[node] = _find(parent, relation, node)


def _merged(
    patch: IndexArray,
    patches: int,
    face: IndexArray,
    starting: BoolArray,
    nonmanifold: IndexArray,
) -> tuple[IndexArray, int]:
    """Join the patches around each non-manifold edge into components; number them."""
    if not len(nonmanifold):
        return patch, patches
    # Link each later half-edge of a non-manifold edge to the edge's first half-edge.
    first = np.flatnonzero(starting)
    uses = np.diff(np.r_[first, len(face)])[np.searchsorted(first, nonmanifold)]
    group = np.repeat(nonmanifold, uses)
    position = group + np.arange(len(group)) - np.repeat(np.cumsum(uses) - uses, uses)
    one, two = patch[face[group]], patch[face[position]]
    root, _ = _connected(patches, one, two, np.zeros(len(one), dtype=np.intp))
    number, firsts = _numbered(root, np.ones(patches, dtype=bool))
    return np.where(patch >= 0, number[patch], -1), len(firsts)


def _numbered(root: IndexArray, valid: BoolArray) -> tuple[IndexArray, IndexArray]:
    """Number the roots 0, 1, ... in order; -1 for invalid nodes. Also returns the roots."""
    is_root = valid & (root == np.arange(len(root)))
    number = np.cumsum(is_root) - 1
    return np.where(valid, number[root], -1), np.flatnonzero(is_root)


# --- geometry and decisions ------------------------------------------------------------------


def _cone_terms(
    points: FloatArray, faces: IndexArray, group: IndexArray, groups: int
) -> tuple[FloatArray, FloatArray, int]:
    """det(A - c, B - c, C - c) of each face and its bound |n| |A - c|, c its group's centroid.

    The vertices are first divided by 2**scale (exact) so that the largest |coordinate| is in
    [0.5, 1): the terms are 2**(-3 scale) times the true ones. c is the area-weighted centroid
    of the face centroids A + (B - A + C - A) / 3 of each group; in a group of zero area
    every normal is zero, and so is every term whatever c is.
    """
    points, factor, scale = scaling(points)
    count = len(faces)
    terms, bounds = np.empty(count), np.empty(count)
    sums = np.zeros((groups, 4))  # area-weighted centroid sums and the area, per group
    _cone_kernel(points, factor, faces, group, sums, terms, bounds)
    return terms, bounds, scale


@njit(cache=True, error_model="numpy")
def _cone_face(
    points: FloatArray, factor: float, faces: IndexArray, face: int
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """A, and the cross product n = (B - A) x (C - A) and the centroid of one face, scaled."""
    a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
    ax, ay, az = points[a, 0] * factor, points[a, 1] * factor, points[a, 2] * factor
    ux, uy, uz = points[b, 0] * factor - ax, points[b, 1] * factor - ay, points[b, 2] * factor - az
    vx, vy, vz = points[c, 0] * factor - ax, points[c, 1] * factor - ay, points[c, 2] * factor - az
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    return ax, ay, az, nx, ny, nz, (ux + vx) / 3 + ax, (uy + vy) / 3 + ay, (uz + vz) / 3 + az


@njit(cache=True, error_model="numpy")
def _cone_kernel(
    points: FloatArray,
    factor: float,
    faces: IndexArray,
    group: IndexArray,
    sums: FloatArray,
    terms: FloatArray,
    bounds: FloatArray,
) -> None:
    """Two passes over the faces: the groups' centroids, then each face's term and bound."""
    for face in range(len(faces)):
        _, _, _, nx, ny, nz, cx, cy, cz = _cone_face(points, factor, faces, face)
        area = math.sqrt(nx * nx + ny * ny + nz * nz)
        row = sums[group[face]]
        row[0] += area * cx
        row[1] += area * cy
        row[2] += area * cz
        row[3] += area
    for row in sums:
        total = row[3] if row[3] != 0.0 else 1.0
        row[0], row[1], row[2] = row[0] / total, row[1] / total, row[2] / total
    for face in range(len(faces)):
        ax, ay, az, nx, ny, nz, _, _, _ = _cone_face(points, factor, faces, face)
        row = sums[group[face]]
        dx, dy, dz = ax - row[0], ay - row[1], az - row[2]
        terms[face] = nx * dx + ny * dy + nz * dz
        bounds[face] = math.sqrt(nx * nx + ny * ny + nz * nz) * math.sqrt(
            dx * dx + dy * dy + dz * dz
        )


def _unscaled(value: float, scale: int) -> float:
    with np.errstate(over="ignore"):
        return float(np.ldexp(value, 3 * scale)) + 0.0


def _unscaled_array(values: FloatArray, scale: int) -> FloatArray:
    with np.errstate(over="ignore"):
        return np.ldexp(values, 3 * scale)


def _combined(votes: IndexArray) -> int:
    """The common vote, ignoring undetermined ones; mixed if they differ."""
    cast = np.bincount(votes, minlength=4)
    kinds = np.flatnonzero(cast[:_UNDETERMINED])
    if len(kinds) == 0:
        return _UNDETERMINED
    return int(kinds[0]) if len(kinds) == 1 else _MIXED


def _component_table(
    structure: _Structure,
    decided: BoolArray,
    vote: IndexArray,
    flips: IndexArray,
    size: FloatArray,
    volume: FloatArray,
) -> ComponentTable:
    """Sum the patches up by component."""
    count = structure.topology.components
    of_patch = structure.patch_component

    def any_patch(mask: BoolArray) -> BoolArray:
        return np.bincount(of_patch, mask, count) > 0

    orientable = ~any_patch(~structure.orientable)
    closed = structure.closed
    has_volume = closed & orientable
    # A closed component is one patch, so its volume is that patch's.
    component_volume = np.zeros(count)
    closed_patch = has_volume[of_patch]
    component_volume[of_patch[closed_patch]] = volume[closed_patch]
    method = np.where(any_patch(decided), np.where(closed, _VOLUME, _HEURISTIC), _NONE)
    votes = np.stack([any_patch(vote == v) for v in range(_UNDETERMINED)])
    kinds = votes.sum(axis=0)
    orientation = np.where(
        kinds == 0, _UNDETERMINED, np.where(kinds == 1, np.argmax(votes, axis=0), _MIXED)
    )
    return ComponentTable(
        faces=np.bincount(of_patch, size, count).astype(np.intp),
        closed=closed,
        orientable=orientable,
        method=method,
        flipped=np.bincount(of_patch, flips, count).astype(np.intp),
        volume=component_volume,
        has_volume=has_volume,
        orientation=orientation,
    )
