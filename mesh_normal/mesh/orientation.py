"""Which way the faces of a triangle mesh point, and turning them all outward: :func:`orient`.

The terms (edge, patch, component, consistent winding) are those of
:mod:`mesh_normal.mesh.topology`,
by position: vertices with identical coordinates are one point (and, with ``weld``, vertices
closer than that fraction of the bounding-box diagonal), so pieces that close up together,
such as a cube whose six sides each have their own vertices, are one patch and are decided
together. A patch consistently wound with its neighbours by position is one patch with them
and is never flipped against them, so the fix never turns a mesh that is consistently wound
by position into one that is not.

Which way is out. :func:`orient` first makes each orientable patch consistent, then decides
which side is out:

- *A closed patch* by the sign of its volume V = sum of det(A - c, B - c, C - c) / 6 over its
  faces (c its area-weighted centroid; for a closed surface V does not depend on c), positive
  when the faces point outward (method ``"volume"``).
- *An open patch* by visibility from outside (method ``"visibility"``, see
  :mod:`mesh_normal.mesh.visibility`): rays leave sample faces on both sides, and the side from
  which more of them escape past every face of the whole mesh is out. So separate pieces are
  judged together: the inside of a bowl sees the bowl, the inner sides of a box whose sides
  are separate patches see each other, the inner side of a car's panel sees the other
  panels, and range scans that faced their scanner see it. A cone-volume heuristic per patch
  (the convex side out, as Blender's "Recalculate Outside" picks) would judge each piece
  alone and turn correctly wound separate pieces over.

On evidence only. A closed patch's volume decides only when it is clearly more than noise, by
two tests relative to the patch's own size and position (so the verdict is the same wherever
the mesh is, however it is turned and scaled):

- *Flatness*: |V| must exceed ``MESH_FLAT_SINE`` (2**-37) times sum |n| |A - c| / 6 (what V
  would be if every face faced straight away from c): a closed surface enclosing nothing (two
  faces back to back) is flat.
- *Rounding*: |V| must exceed ``ORIENT_EVIDENCE`` times the most that V could move if every
  coordinate moved by its rounding (the float32 or float64 unit, whichever the coordinates
  are, times the patch's largest |coordinate|: a patch far from the origin is rounded more),
  plus the float error of computing V.

An open patch is decided only when the escaping shares of its two sides differ by at least
:data:`mesh_normal.mesh.visibility.MARGIN`: a plane sheet, a gently curved scan or a single
triangle sees the world alike from both sides, a plate shut inside a box from neither, and
they are undetermined. A patch made only of faces that lie back to back with another face
(a double-sided surface) is not scored at all: turning it would only make two faces one.

Shells inside shells. Every surface faces away from the material: a closed patch with an
evident volume that lies inside an even number of others (its *depth*) faces out, one inside an
odd number faces in (a cavity, or the surface of a body inside a cavity faces out again). A shell
lies inside another when its box lies within the other's and sample vertices of it are at a
generalized winding number of 1 about the other, taken only where the samples are clearly off
the other's surface (see :func:`_nesting`). A shell that crosses another (an eye sunk half into
a head) is no cavity of it but a body of its own, and that other does not count in its depth. A
shell that touches another (a sample on or within rounding of its surface) has no known depth
and is undetermined. So :func:`orient` flips nothing on a closed mesh whose shells all face away
from the material.

A patch that fails any of these tests is *undetermined*: :func:`orient` does not turn it over, only
makes it consistent, keeping the winding of the majority of its faces (of its lowest-numbered
face on a tie). A non-orientable patch is left as it is.

On the benchmark torus of 871,414 faces (``benchmarks/mesh_kernels.py``), the
position welding (one hash sort of the vertices) and the error bounds (one more pass in the
cone kernel) cost about 10 to 15 percent of :func:`orient`'s time.

One pass. :func:`orient` returns the topology too, so a caller that needs both calls only
:func:`orient`; given a :class:`~mesh_normal.mesh.faces.FaceGeometry` it reuses its cross products
for the cone terms instead of computing them again (only where a face's product was retaken
at another corner is it taken at A once more, so that the volume keeps its bits).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from typing import overload

import numpy as np
from numpy.typing import ArrayLike

import mesh_normal._core as _core
from mesh_normal.choices import Method as Method
from mesh_normal.choices import Verdict as Verdict
from mesh_normal.mesh.checks import CheckedMesh
from mesh_normal.mesh.faces import FaceGeometry, MeshInput, checked_input, face_geometry
from mesh_normal.mesh.topology import KEY_LIMIT, Structure, by_position, structure
from mesh_normal.mesh.topology import (
    MeshTopology as MeshTopology,  # re-exported: Orientation has one
)
from mesh_normal.mesh.visibility import MARGIN as VISIBILITY_MARGIN
from mesh_normal.mesh.visibility import Framed, framed, visible_sides
from mesh_normal.tolerances import (
    EPSILON,
    FLOAT32_UNIT,
    MESH_FLAT_SINE,
    ORIENT_EVIDENCE,
)
from mesh_normal.types import BoolArray, FloatArray, IndexArray, ParityArray

VERDICTS: tuple[Verdict, ...] = ("outward", "inward", "mixed", "undetermined")
METHODS: tuple[Method, ...] = ("volume", "visibility", "none")

_OUTWARD, _INWARD, _MIXED, _UNDETERMINED = range(4)
_VOLUME, _VISIBILITY, _NONE = range(3)


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
    method : {"volume", "visibility", "none"}
        How its outside was chosen: by the sign of its volume (closed and orientable), by
        visibility from outside (open; at least one patch decided), or not at all
        (non-orientable, a closed surface enclosing no volume, a shell that touches another, a
        volume whose sign could be rounding noise, or an open part that sees alike from both
        sides). A closed part's volume is compared with its depth: out at even depth, in at odd.
    flipped : int
        How many of its faces :func:`orient` reversed.
    volume : float or None
        Its signed volume after orienting, when closed and orientable (negative for a cavity:
        the volumes sum to the material's); else None.
    orientation : {"outward", "inward", "mixed", "undetermined"}
        Its verdict as given (see :attr:`Orientation.orientation`).
    depth : int or None
        How many other closed components it lies inside, when it is closed with a volume
        clearly more than noise and that is known: even, it faces out; odd, it is a cavity and
        faces in. None otherwise.
    inside : int or None
        The innermost closed component it lies inside, or None.
    touches : int or None
        A closed component it touches, so that its depth is not known (it is not turned), or
        None.
    """

    index: int
    faces: int
    closed: bool
    orientable: bool
    method: Method
    flipped: int
    volume: float | None
    orientation: Verdict
    depth: int | None = None
    inside: int | None = None
    touches: int | None = None


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
    depth, inside, touches : (c,) intp
        As in :class:`ComponentOrientation`, -1 for None.
    """

    faces: IndexArray
    closed: BoolArray
    orientable: BoolArray
    method: IndexArray
    flipped: IndexArray
    volume: FloatArray
    has_volume: BoolArray
    orientation: IndexArray
    depth: IndexArray
    inside: IndexArray
    touches: IndexArray

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
            depth=_optional(self.depth[i]),
            inside=_optional(self.inside[i]),
            touches=_optional(self.touches[i]),
        )

    def __iter__(self) -> Iterator[ComponentOrientation]:
        return (self[i] for i in range(len(self)))


def _optional(value: np.intp) -> int | None:
    return None if value < 0 else int(value)


@dataclass(frozen=True, slots=True)
class Orientation:
    """The result of :func:`orient`.

    Attributes
    ----------
    faces : (m, 3) intp
        The input faces, rows ``[a, b, c]`` that were flipped as ``[a, c, b]``; when none
        was, a read-only view of the input's faces (no copy of 24 bytes a face).
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


def signed_volume(vertices: MeshInput, faces: ArrayLike | None = None) -> float:
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
    vertices : (n, 3) float64, CheckedMesh or FaceGeometry
        Finite coordinates, or an already checked mesh or its geometry (then no ``faces``).
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
    source = checked_input(vertices, faces)
    count = len((source.mesh if isinstance(source, FaceGeometry) else source).faces)
    if not count:
        return 0.0
    cone = _cone_terms(face_geometry(source), np.zeros(count, dtype=np.intp), 1)
    return _unscaled(float(np.sum(cone.terms)) / 6, cone.scale)


def orient(
    vertices: MeshInput, faces: ArrayLike | None = None, *, weld: float | None = None
) -> Orientation:
    """Make the winding consistent and outward, patch by patch, and report what changed.

    Parameters
    ----------
    vertices : (n, 3) float64, CheckedMesh or FaceGeometry
        Finite coordinates, which are not changed, or an already checked mesh or its
        geometry (then no ``faces``).
    faces : (m, 3) int
        Indices into ``vertices``.
    weld : float, optional
        Also treat vertices closer than this fraction of the bounding-box diagonal as one
        point (see :func:`mesh_normal.mesh.topology.same_points`); off by default, when only
        vertices with identical coordinates are.

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
    mesh = checked_input(vertices, faces)
    if isinstance(mesh, FaceGeometry):
        return oriented(mesh, by_position(mesh.mesh, weld))
    points = by_position(mesh, weld)
    ahead = HeadStart(mesh, points)
    try:
        found = structure(points, len(mesh.vertices), ahead.start)  # before the products: see
        return oriented(face_geometry(mesh), points, found, ahead)  # analyse_mesh
    finally:
        ahead.finish()


#: Meshes of this many faces or more take an open mesh's twins and Morton order ahead, on
#: another thread (:class:`HeadStart`); smaller ones in turn.
HEAD_START_FACES = 1 << 16


class HeadStart:
    """What only an open mesh's orientation needs, and only from its points: which faces are
    twinned (:func:`_twinned`) and the frame and Morton order of the rays' hierarchy
    (:func:`~mesh_normal.mesh.visibility.framed`), taken on another thread from when
    :func:`~mesh_normal.mesh.topology.structure` finds a boundary edge (:meth:`start`), while the
    topology's one-thread passes (union-find) keep one core. The same arrays as taken in turn;
    without :meth:`start` (a closed mesh, or a small one) they are taken in turn when asked for.

    The compiled kernels release the GIL while they run, so that each thread's Python between
    kernels is not held up by the other's kernel.
    """

    def __init__(self, mesh: CheckedMesh, points: IndexArray) -> None:
        self._mesh, self._points = mesh, points
        self._thread: threading.Thread | None = None
        self._twins: BoolArray | None = None
        self._frame: Framed | None = None
        self._error: BaseException | None = None

    def start(self) -> None:
        """Start the thread (once), for a mesh of ``HEAD_START_FACES`` faces or more."""
        if self._thread is None and len(self._points) >= HEAD_START_FACES:
            thread = threading.Thread(target=self._run, name="mesh-normal-ahead")
            try:
                thread.start()
            except RuntimeError:  # no thread to be had (a memory limit): taken in turn instead
                return
            self._thread = thread

    def _run(self) -> None:
        try:
            self._twins = _twinned(self._points)
            self._frame = framed(self._mesh.vertices, self._mesh.faces)
        except BaseException as error:  # raised again where the result is asked for
            self._error = error

    def _joined(self) -> bool:
        if self._thread is None:
            return False
        self._thread.join()
        if self._error is not None:
            raise self._error
        return True

    def twinned(self) -> BoolArray:
        """:func:`_twinned` of the points."""
        if self._joined() and self._twins is not None:
            twins, self._twins = self._twins, None
            return twins
        return _twinned(self._points)

    def frame(self) -> Framed | None:
        """:func:`~mesh_normal.mesh.visibility.framed` of the mesh."""
        if self._joined():
            frame, self._frame = self._frame, None
            return frame
        return framed(self._mesh.vertices, self._mesh.faces)

    def finish(self) -> None:
        """Wait for the thread, if it was started, and let its results go: for its owner once
        the orientation is done (or failed), so that none of this mesh's work goes on after
        it, even where no open patch was scored after all and nothing was asked for."""
        if self._thread is not None:
            self._thread.join()
        self._twins = self._frame = None


def oriented(
    geometry: FaceGeometry,
    points: IndexArray,
    found: Structure | None = None,
    ahead: HeadStart | None = None,
) -> Orientation:
    """:func:`orient` on a geometry whose faces by position (each vertex replaced by the first
    at its point, as :func:`~mesh_normal.mesh.topology.by_position` gives them) are known already:
    for a caller that needs them too, so that the vertices are matched once. ``found`` is
    their :func:`~mesh_normal.mesh.topology.structure` if the caller took it already, and
    ``ahead`` the :class:`HeadStart` it gave that call."""
    indices = geometry.mesh.faces
    if found is None:
        found = structure(points, len(geometry.mesh.vertices))
    topology, group, parity = found.topology, found.group, found.parity
    bins = found.patches + 1  # the last for faces with a repeated point

    def per_patch(weights: FloatArray | ParityArray | None = None) -> FloatArray:
        # np.bincount's sums (in face order, the same bits), without the copies it makes of
        # a read-only group array (8 bytes a face) and of weights that are not float64.
        sums = np.zeros(bins)
        if weights is None:
            _core.count_by_group(group, sums)
        else:
            _core.sum_by_group(group, weights, sums)
        return sums[:-1]

    size, against = per_patch(), per_patch(parity)
    cone = _cone_terms(geometry, group, bins)
    terms, scale = cone.terms, cone.scale
    terms_sum = float(np.sum(terms))  # the input's volume, if it is closed and consistent
    # The volume of each patch with its winding made consistent, its first face unchanged:
    # the terms turned in place (the copies np.where makes are 16 bytes a face).
    np.negative(terms, out=terms, where=parity.view(bool))
    volume = per_patch(terms) / 6
    orientable = found.orientable
    closed = found.closed[found.patch_component]
    shells = orientable & closed & _evident(volume, cone, len(indices))
    del terms  # 8 bytes a face, not needed from here on
    cone = replace(cone, terms=np.empty(0))
    # Every surface faces away from the material: a shell that lies in an even number of
    # others faces out, in an odd number in (a cavity). A shell whose depth is not known
    # (it touches another) is left as it is.
    nesting = _nesting(geometry, found, shells, cone)
    shells &= nesting.depth >= 0
    cavity = nesting.depth % 2 == 1
    # Open patches: the side from which the rest of the mesh and the world beyond are seen.
    area = per_patch(geometry.lengths)
    # A patch made only of faces back to back with another face (a double-sided surface, on
    # purpose or not) is left as it is: turning it would only make two faces one.
    open_patches = orientable & ~closed & (area > 0)
    if ahead is None:
        ahead = HeadStart(geometry.mesh, points)
    if open_patches.any():  # a closed mesh has none: no key a face to sort
        open_patches &= per_patch((~ahead.twinned()).view(np.int8)) > 0
    score = visible_sides(
        geometry.mesh.vertices, indices, group, parity, open_patches, area, ahead.frame
    )
    seen = np.abs(np.nan_to_num(score)) >= VISIBILITY_MARGIN
    inward = score < 0
    decided = shells | seen
    # Turn the consistent patch over when it points in, or when most of its faces are against
    # its first face (undecided patches).
    turn = np.where(shells, (volume < 0) != cavity, np.where(seen, inward, 2 * against > size))
    flips = np.where(orientable, np.where(turn, size - against, against), 0).astype(np.intp)
    flipped = (parity ^ np.r_[turn, False][group]).astype(bool)
    flipped &= np.r_[orientable, False][group]
    vote = np.where(flips == 0, _OUTWARD, np.where(flips == size, _INWARD, _MIXED))
    vote[~decided] = np.where(flips[~decided] > 0, _MIXED, _UNDETERMINED)
    vote[~orientable] = _UNDETERMINED
    after = _unscaled_array(np.where(turn, -volume, volume), scale)
    components = _component_table(found, decided, vote, flips, size, after, nesting)
    if flipped.any():
        oriented = indices.copy()
        oriented[flipped, 1:] = indices[flipped, :0:-1]
    else:
        oriented = indices.view()
        oriented.flags.writeable = False
    input_volume = None
    if topology.watertight and topology.winding_consistent:
        input_volume = _unscaled(terms_sum / 6, scale)
    return Orientation(
        oriented, flipped, VERDICTS[_combined(vote)], components, input_volume, topology
    )


# --- geometry and decisions ------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Cone:
    """What :func:`_cone_terms` returns, in the vertices scaled by ``2**-scale``."""

    terms: FloatArray  # (m,) det(A - c, B - c, C - c)
    # Summed by group (k,), not kept a face (16 bytes a face fewer while orient() runs):
    bounds: FloatArray  # sum of |n| |A - c|: the term if the face faced straight away from c
    sensitivity: FloatArray  # sum of how much the term moves per unit move of A, B, C or c
    largest: FloatArray  # (groups,) the largest |coordinate| of each group's faces
    data_unit: float  # the relative precision of the coordinates (float32 or float64)
    scale: int


def _cone_terms(geometry: FaceGeometry, group: IndexArray, groups: int) -> _Cone:
    """det(A - c, B - c, C - c) of each face, its bounds, c its group's centroid.

    The vertices are divided by 2**scale (exact) so that the largest |coordinate| is in
    [0.5, 1): the terms are 2**(-3 scale) times the true ones. c is the area-weighted centroid
    of the face centroids A + (B - A + C - A) / 3 of each group; in a group of zero area
    every normal is zero, and so is every term whatever c is. n is the geometry's cross
    product, always as taken at corner A (retaken there where the geometry's was not).

    Sensitivity. Moving A by d changes the term by d . ((B - c) x (C - c)), and
    (B - c) x (C - c) = n + (A - c) x (C - B); so the term moves by at most
    |d| (3 |n| + |A - c| |C - B| + |B - c| |A - C| + |C - c| |B - A|) when each corner moves
    by |d|, and by |d| |n| more when c does: the sensitivity is the factor of |d|.
    """
    mesh = geometry.mesh
    count = len(mesh.faces)
    crosses, recomputed = geometry.crosses, geometry.recomputed
    terms = np.empty(count)
    # Per group: the area-weighted centroid sums, the area, the largest |x|, and the sums of
    # the bounds and the sensitivities (summed in face order, as np.bincount sums them: the
    # same bits, without two arrays of 8 bytes a face).
    sums = np.zeros((groups, 7))
    # Chunk by chunk, each face's share is taken on every core and then added into its group
    # in face order on one (the same bits on any number of cores); first the centroids, then
    # the terms and their bounds, which need them.
    _core.cone_sums(mesh.points, mesh.factor, mesh.faces, crosses, recomputed, group, terms, sums)
    unit = FLOAT32_UNIT if _single(mesh.vertices) else EPSILON
    return _Cone(terms, sums[:, 5].copy(), sums[:, 6].copy(), sums[:, 4].copy(), unit, mesh.scale)


#: Rows of vertices compared with their float32 rounding at a time (so that the copy is small).
_SINGLE_BLOCK = 65_536


def _single(points: FloatArray) -> bool:
    """Whether every coordinate is a float32 value, checked a block at a time."""
    with np.errstate(over="ignore"):  # beyond the float32 range is not float32 data
        for start in range(0, len(points), _SINGLE_BLOCK):
            block = points[start : start + _SINGLE_BLOCK]
            if not np.array_equal(block.astype(np.float32), block):
                return False
    return True


def _evident(
    volume: FloatArray,
    cone: _Cone,
    count: int,
) -> BoolArray:
    """Which patches' volume V has a sign that does not hinge on rounding (see the docstring).

    Two tests, both relative to the patch itself. Flatness: |V| > MESH_FLAT_SINE
    sum |n||A-c| / 6. Evidence:
    |V| exceeds ORIENT_EVIDENCE times the most that V could move if every coordinate of the
    patch moved by its rounding, u |x| (u the unit of the coordinates' precision, float32 or
    float64; |x| the patch's largest coordinate, so the bound grows with the distance from
    the origin just as the rounding does), plus the float error of computing V (about
    (8 + log2 m) eps sum |n||A-c|, see :func:`signed_volume`).
    """
    bounds = cone.bounds[: len(volume)]
    move = (cone.data_unit + 4 * EPSILON) * cone.largest[: len(volume)]
    error = move * cone.sensitivity[: len(volume)] + (8 + math.log2(count + 1)) * EPSILON * bounds
    magnitude = 6 * np.abs(volume)
    flat = MESH_FLAT_SINE * bounds
    return (magnitude > flat) & (magnitude > ORIENT_EVIDENCE * error)


# --- shells inside shells ----------------------------------------------------------------------

#: How many vertices of a closed shell are tested for lying inside another (spread over its
#: faces), and at most how many vertices of the other that lie in its box for lying inside it.
_NEST_SAMPLES = 32
#: A sample counts only this far from the other shell, relative to that shell's box diagonal (the
#: winding number is then certain, see :func:`_nesting`); nearer, the shells touch.
_NEST_CLEARANCE = 2.0**-30
#: At most this many pairs of boxes one inside the other are looked at; past it, a shell whose
#: box lies inside another's has no known depth (undetermined, never flipped).
_NEST_PAIRS = 1 << 16
#: At most this many comparisons of two boxes go into finding the pairs; past it no shell whose
#: box overlaps others has a known depth.
_NEST_COMPARISONS = 1 << 26
#: At most this many (sample, face) visits go into winding numbers; the pairs past it (in the
#: order of the inner shell) are not tested, and their inner shell has no known depth.
_NEST_WORK = 2 * 10**8

#: The samples of a shell tested first, for lying inside another: one clearly outside settles it.
_NEST_FIRST = 4

# How a shell K whose box lies within J's relates to J: not inside it (outside, or crossing
# it), inside, touching it (not known which), not tested (past the limits).
_APART, _INSIDE, _TOUCHES, _UNTESTED = range(4)


@dataclass(frozen=True, slots=True)
class _Nesting:
    """Per patch: ``depth``, how many closed shells hold it (-1: not a shell, or unknown: it
    touches one, or was past the limits); ``parent``, the innermost of them (-1: none);
    ``touches``, a shell it touches (-1: none)."""

    depth: IndexArray
    parent: IndexArray
    touches: IndexArray


def _nesting(
    geometry: FaceGeometry, found: Structure, candidates: BoolArray, cone: _Cone
) -> _Nesting:
    """How deep each of the ``candidates`` (closed patches with an evident volume) lies in the
    others, by the generalized winding number.

    A shell J holds a shell K when K's box lies within J's and K lies inside J's solid: each of
    up to ``_NEST_SAMPLES`` vertices of K, spread over its faces, has a winding number about J
    (J's winding made consistent) of 1 in magnitude (0 outside a closed surface), and no vertex
    of J that lies in K's box is inside K. A winding number is trusted only at a sample farther
    from J than ``_NEST_CLEARANCE`` of J's box diagonal plus ``ORIENT_EVIDENCE`` times the
    coordinates' rounding (as for the volume: the same verdict wherever the mesh is): there
    the float sum of the solid angles is within far less than one half of the integer it
    stands for, and it is rounded. Then:

    - a sample clearly outside J, or a vertex of J clearly inside K: K is not inside J. It lies
      beside J in J's box, or crosses J (an eye sunk half into a head): no cavity of J (a
      cavity cannot break through the material's surface) but a body of its own. J does not
      count in its depth;
    - else a sample (or such a vertex of J) nearer than that: they touch, and K's depth is
      unknown;
    - else every sample inside: K lies in J, and counts J in its depth.

    Boxes one inside the other are found by a sweep (:func:`_contained`); past ``_NEST_PAIRS``
    such pairs, or ``_NEST_WORK`` face visits, the shells not tested have no known depth.
    """
    patches = found.patches
    depth = np.full(patches, -1, dtype=np.intp)
    parent = np.full(patches, -1, dtype=np.intp)
    touches = np.full(patches, -1, dtype=np.intp)
    shells = np.flatnonzero(candidates)
    depth[shells] = 0
    if len(shells) < 2:
        return _Nesting(depth, parent, touches)
    mesh = geometry.mesh
    group = found.group
    member = np.flatnonzero(np.r_[candidates, False][group])
    order = member[np.argsort(group[member], kind="stable")]
    starts = np.searchsorted(group[order], shells)
    ends = np.searchsorted(group[order], shells, side="right")
    low = np.full((len(shells), 3), np.inf)
    high = np.full((len(shells), 3), -np.inf)
    for corner in range(3):  # a corner at a time: 24 bytes a face at most
        points = mesh.points[mesh.faces[order, corner]] * mesh.factor
        low = np.minimum(low, np.minimum.reduceat(points, starts))
        high = np.maximum(high, np.maximum.reduceat(points, starts))
    del points
    pairs, boxed = _contained(low, high)
    if pairs is None:  # too many to test: a shell in another's box has no known depth
        depth[shells[boxed]] = -1
        return _Nesting(depth, parent, touches)
    relation = _relations(mesh, found, order, starts, ends, low, high, pairs, shells, cone)
    inner, outer = pairs[:, 0], pairs[:, 1]
    holds = relation == _INSIDE
    count = np.bincount(inner[holds], minlength=len(shells))
    unknown = np.zeros(len(shells), dtype=bool)
    for kind, mark in ((_TOUCHES, touches), (_UNTESTED, None)):
        rows = np.flatnonzero(relation == kind)
        unknown[inner[rows]] = True
        if mark is not None:  # the first shell it touches, by number
            first = rows[np.lexsort((shells[outer[rows]], inner[rows]))]
            keep = np.r_[True, inner[first][1:] != inner[first][:-1]] if len(first) else first
            mark[shells[inner[first[keep]]]] = shells[outer[first[keep]]]
    depth[shells] = np.where(unknown, -1, count)
    # The innermost shell that holds it: of those, the one with the smallest box.
    size = np.linalg.norm(high - low, axis=1)
    holding = np.flatnonzero(holds)
    holding = holding[np.lexsort((size[outer[holding]], inner[holding]))]
    first = np.r_[True, inner[holding][1:] != inner[holding][:-1]] if len(holding) else holding
    parent[shells[inner[holding[first]]]] = shells[outer[holding[first]]]
    return _Nesting(depth, parent, touches)


def _contained(low: FloatArray, high: FloatArray) -> tuple[IndexArray | None, BoolArray]:
    """The pairs (k, j) of boxes where box k lies within box j, or None past ``_NEST_PAIRS``;
    and which boxes lie within another. Swept along the axis that separates the boxes best
    (the largest span of the whole over the boxes' mean extent)."""
    span = high.max(axis=0) - low.min(axis=0)
    extent = (high - low).mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        axis = int(np.argmax(np.nan_to_num(span / extent, nan=0.0, posinf=np.inf)))
    pairs = np.empty((_NEST_PAIRS, 2), dtype=np.int64)
    boxed = np.zeros(len(low), dtype=bool)
    total = _core.contained_boxes(low, high, axis, _NEST_COMPARISONS, pairs, boxed)
    if total < 0:  # boxes that overlap each other by the thousand: none has a known depth
        return None, np.ones(len(low), dtype=bool)
    if total > _NEST_PAIRS:
        return None, boxed
    kept = pairs[:total]
    return kept[np.lexsort((kept[:, 1], kept[:, 0]))].astype(np.intp), boxed


def _relations(
    mesh: CheckedMesh,
    found: Structure,
    order: IndexArray,
    starts: IndexArray,
    ends: IndexArray,
    low: FloatArray,
    high: FloatArray,
    pairs: IndexArray,
    shells: IndexArray,
    cone: _Cone,
) -> IndexArray:
    """(pairs,) how each inner shell relates to its outer one (see :func:`_nesting`).

    In three steps, each on the pairs not yet settled: ``_NEST_FIRST`` samples (one clearly
    outside settles most pairs of shells side by side in one box), then ``_NEST_SAMPLES``, then
    the outer shell's vertices in the inner one's box."""
    relation = np.full(len(pairs), _UNTESTED, dtype=np.intp)
    if not len(pairs):
        return relation
    inner, outer = pairs[:, 0], pairs[:, 1]
    faces = ends - starts
    oriented: dict[int, IndexArray] = {}

    def oriented_faces(shell: int) -> IndexArray:
        if shell not in oriented:
            rows = order[starts[shell] : ends[shell]]
            turned = found.parity[rows].astype(bool)
            chosen = mesh.faces[rows]
            chosen[turned, 1:] = chosen[turned, :0:-1]
            oriented[shell] = chosen
        return oriented[shell]

    def spread(shell: int, count: int) -> FloatArray:
        picks = np.linspace(starts[shell], ends[shell] - 1, min(count, faces[shell]))
        chosen: FloatArray = mesh.points[mesh.faces[order[picks.astype(np.intp)], 0]]
        return chosen * mesh.factor

    # The most that the three steps can cost, in (sample, face) visits.
    work = _NEST_SAMPLES * (faces[outer] + faces[inner])
    pending = np.cumsum(work) <= _NEST_WORK
    # A sample is trusted this far from the other shell: a fraction of that shell's size, and
    # the coordinates' rounding (as for the volume's evidence), so anywhere alike.
    largest = cone.largest[: found.patches][shells]
    noise = ORIENT_EVIDENCE * (cone.data_unit + 4 * EPSILON) * largest
    reach = _NEST_CLEARANCE * np.linalg.norm(high - low, axis=1)
    for count in (_NEST_FIRST, _NEST_SAMPLES):  # the inner shells' samples about the outer
        samples = {k: spread(k, count) for k in np.unique(inner[pending]).tolist()}
        for j, rows in _grouped(outer, pending):
            groups = [samples[int(inner[r])] for r in rows]
            limits = [reach[j] + max(noise[j], noise[inner[r]]) for r in rows]
            inside, outside, near = _sorted_samples(mesh, oriented_faces(j), groups, limits).T
            relation[rows] = np.where(outside > 0, _APART, _UNTESTED)
            if count == _NEST_SAMPLES:
                relation[rows] = np.where(
                    outside > 0, _APART, np.where(near > 0, _TOUCHES, _INSIDE)
                )
        pending &= relation == _UNTESTED
    # The vertices of the outer shell that lie in the inner one's box, at most _NEST_SAMPLES
    # spread among them, about the inner shell: one inside it, and they cross.
    maybe = relation == _INSIDE
    vertices: dict[int, FloatArray] = {}  # each outer shell's, sorted along x
    for k, rows in _grouped(inner, maybe):
        groups, limits = [], []
        for r in rows:
            j = int(outer[r])
            if j not in vertices:
                used = mesh.points[np.unique(oriented_faces(j))] * mesh.factor
                vertices[j] = used[np.argsort(used[:, 0], kind="stable")]
            ranked = vertices[j]
            first = np.searchsorted(ranked[:, 0], low[k, 0], side="left")
            slab = ranked[first : np.searchsorted(ranked[:, 0], high[k, 0], side="right")]
            picked = slab[np.all((slab >= low[k]) & (slab <= high[k]), axis=1)]
            if len(picked) > _NEST_SAMPLES:
                picked = picked[np.linspace(0, len(picked) - 1, _NEST_SAMPLES).astype(np.intp)]
            groups.append(picked)
            limits.append(reach[k] + max(noise[k], noise[j]))
        if not any(len(group) for group in groups):
            continue
        inside, _, near = _sorted_samples(mesh, oriented_faces(k), groups, limits).T
        relation[rows] = np.where(inside > 0, _APART, np.where(near > 0, _TOUCHES, _INSIDE))
    return relation


def _grouped(keys: IndexArray, chosen: BoolArray) -> Iterator[tuple[int, list[int]]]:
    """Each key of the chosen rows with its rows, in the order of the keys."""
    rows = np.flatnonzero(chosen)
    if not len(rows):
        return
    rows = rows[np.argsort(keys[rows], kind="stable")]
    bounds = np.flatnonzero(np.r_[True, keys[rows][1:] != keys[rows][:-1], True])
    for a, b in zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=True):
        yield int(keys[rows[a]]), rows[a:b].tolist()


def _sorted_samples(
    mesh: CheckedMesh, faces: IndexArray, groups: list[FloatArray], limits: list[float]
) -> IndexArray:
    """(groups, 3): of each group of points, how many lie inside the closed shell ``faces``,
    outside it, and nearer it than the group's limit (where the winding number is not
    trusted)."""
    points = np.ascontiguousarray(np.concatenate(groups))
    winding, clearance = np.empty(len(points)), np.empty(len(points))
    _core.winding_numbers(mesh.points, mesh.factor, faces, points, winding, clearance)
    sizes = [len(group) for group in groups]
    limit = np.repeat(np.array(limits), sizes)
    rounded = np.rint(winding)
    # Far from the surface the sum is within far less than 1/2 of an integer; a sum that is not
    # counts as near all the same.
    clear = (np.sqrt(clearance) > limit) & (np.abs(winding - rounded) < 0.25)
    which = np.repeat(np.arange(len(groups)), sizes)
    inside = np.bincount(which, clear & (rounded != 0), len(groups))
    outside = np.bincount(which, clear & (rounded == 0), len(groups))
    near = np.bincount(which, ~clear, len(groups))
    return np.stack([inside, outside, near], axis=1).astype(np.intp)


def _twinned(faces: IndexArray) -> BoolArray:
    """(m,) bool: which faces have the same three points as another face wound the other way."""
    if len(faces) == 0:
        return np.zeros(0, dtype=bool)
    width = int(faces.max()) + 1
    if width * width * 2 < KEY_LIMIT:
        return _twinned_wide(faces, width)
    return _twinned_lexsorted(faces, _even(faces))


def _even(faces: IndexArray) -> BoolArray:
    """(m,) bool: the face is wound as its sorted points (a rotation of them)."""
    # Two of the three steps a -> b -> c -> a go up, or a point repeats (then some rotation is
    # the sorted order). No rolled copies.
    a, b, c = faces.T
    ascents = (a < b).view(np.int8) + (b < c).view(np.int8) + (c < a).view(np.int8)
    even: BoolArray = (ascents == 2) | (a == b) | (b == c) | (c == a)
    return even


def _twinned_wide(faces: IndexArray, width: int) -> BoolArray:
    """:func:`_twinned` where two points fit one key: the faces grouped by their smallest
    point with a counting sort, then compared within each group (a face's group holds two
    faces on average). At the Lucy size a lexsort of the rows takes about 11 s; a sort of one
    key a face is a little slower than this, and three times slower with a twin."""
    twinned = np.zeros(len(faces), dtype=bool)
    _core.twinned_faces(faces, width, twinned)
    return twinned


def _twinned_lexsorted(faces: IndexArray, even: BoolArray) -> BoolArray:
    """:func:`_twinned` where the points are too many to pack a face into one key."""
    ordered = np.sort(faces, axis=1)
    order = np.lexsort((even, ordered[:, 2], ordered[:, 1], ordered[:, 0]))
    key = ordered[order]
    run = np.cumsum(np.r_[True, np.any(key[1:] != key[:-1], axis=1)]) - 1
    both = (np.bincount(run, even[order]) > 0) & (np.bincount(run, ~even[order]) > 0)
    twinned = np.empty(len(faces), dtype=bool)
    twinned[order] = both[run]
    return twinned


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
    found: Structure,
    decided: BoolArray,
    vote: IndexArray,
    flips: IndexArray,
    size: FloatArray,
    volume: FloatArray,
    nesting: _Nesting,
) -> ComponentTable:
    """Sum the patches up by component."""
    count = found.topology.components
    of_patch = found.patch_component

    def any_patch(mask: BoolArray) -> BoolArray:
        return np.bincount(of_patch, mask, count) > 0

    orientable = ~any_patch(~found.orientable)
    closed = found.closed
    has_volume = closed & orientable
    # A closed component is one patch, so its volume is that patch's.
    component_volume = np.zeros(count)
    closed_patch = has_volume[of_patch]
    component_volume[of_patch[closed_patch]] = volume[closed_patch]
    method = np.where(any_patch(decided), np.where(closed, _VOLUME, _VISIBILITY), _NONE)
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
        depth=_by_component(nesting.depth, found, count),
        inside=_by_component(_component_of(nesting.parent, of_patch), found, count),
        touches=_by_component(_component_of(nesting.touches, of_patch), found, count),
    )


def _component_of(patches: IndexArray, of_patch: IndexArray) -> IndexArray:
    """The component of each patch number, -1 kept."""
    return np.where(patches >= 0, of_patch[np.maximum(patches, 0)], -1)


def _by_component(values: IndexArray, found: Structure, count: int) -> IndexArray:
    """A closed component's value is its one patch's; -1 for the others."""
    result = np.full(count, -1, dtype=np.intp)
    closed = found.closed[found.patch_component]
    result[found.patch_component[closed]] = values[closed]
    return result
