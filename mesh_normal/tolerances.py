"""Every tolerance and limit of the core, in one place.

The single-triangle path has no tolerance at all: it is exact. The batch path is float64
and uses the bounds below to decide which rows it must hand to the exact path.
"""

from __future__ import annotations

import sys

#: Unit roundoff of float64, 2**-53.
EPSILON = sys.float_info.epsilon / 2

#: Shewchuk's bound for a 2x2 determinant of differences, (3 + 16 eps) eps: the float value of
#: ``(b - a)(c - d) - (e - f)(g - h)`` is within this times the sum of the absolute products
#: of the exact value (Shewchuk 1997, "Adaptive Precision Floating-Point Arithmetic").
DETERMINANT_ERROR = (3 + 16 * EPSILON) * EPSILON

#: A batch row keeps its float result only if |n| exceeds this many times the largest
#: error bound of its components; otherwise it is recomputed exactly. The direction of a
#: kept unit normal is then within about sqrt(3) / 2**26 (3e-8) radians of the exact one.
BATCH_MARGIN = 2.0**26

#: Below this, products in the (scaled) batch computation may be subnormal and lose bits.
BATCH_TINY = 2.0**-1000

LARGEST_DOUBLE_TEXT = "about 1.8e308"

#: Trial divisors that :func:`mesh_normal.triangle.exact.square_root` tries when it pulls squares
#: out of a radicand (up to about 5,000 divisions, well under a millisecond on 100-digit integers).
SURD_TRIAL_LIMIT = 10_000

# Meshes (mesh_normal.mesh.faces, mesh_normal.mesh.vertices). These are relative, so a mesh in
# millimetres and the same mesh in metres get the same verdicts.

#: k in the degenerate-face test |n| <= k * EPSILON * |p| * |q|, where n is the cross product
#: of a face's edges p and q at its largest corner (its two shortest edges), i.e. the sine of
#: its largest angle is at most k * EPSILON = 2**-37 (about 7.3e-12). The float n is within
#: about 6 * EPSILON * |p| * |q| of the exact one, so below this bound its direction is
#: rounding noise, and above it a kept normal points within 6 / k (1e-4) radians of the
#: exact direction in the worst case (at the bound). A right triangle with 1e-7 edges has
#: a sine of 1 and is not degenerate, whatever the unit.
MESH_DEGENERATE_FACTOR = 2.0**16
MESH_DEGENERATE_SINE = MESH_DEGENERATE_FACTOR * EPSILON

#: A face's cross product is first taken at its corner A. If the sine of that angle is at
#: most this, it is taken again at the largest corner (between the two shortest edges),
#: where it is most accurate. Faces kept from the first pass point within
#: 6 * EPSILON / 2**-10 (7e-13) radians of the exact direction.
MESH_RECOMPUTE_SINE = 2.0**-10

#: A vertex (or corner) whose weighted sum of unit face normals is at most this fraction of
#: the sum of its weights gets no normal: its faces cancel (a sheet folded flat onto itself)
#: and the direction that is left is rounding noise.
MESH_CANCELLED_SUM = 2.0**-32

#: Two faces are within the crease angle when the dot product of their unit normals is at
#: least cos(crease) minus this, so that a dihedral angle exactly at the crease counts as
#: smooth despite rounding (a cube's faces at a crease of exactly 90 degrees).
MESH_CREASE_SLACK = 16 * EPSILON

#: The corner normals compare pairs of corners around a vertex; at most this many pairs
#: (about 20 bytes each) are held in memory at once.
MESH_PAIR_CHUNK = 2**20

#: The corner normals are made and written this many faces at a time (72 bytes each), so
#: that the (m, 3, 3) result of a large mesh is never whole in a server's memory.
MESH_CORNER_BLOCK = 4096

#: A mesh patch is flat when |V| <= MESH_FLAT_SINE * sum |det| / 6 (V: the volume of the cone
#: from its centroid over its faces, see :mod:`mesh_normal.mesh.orientation`): its faces tilt, on
#: average, by an angle whose sine is at most this towards or away from the centroid. The same
#: bound as a degenerate face's largest angle: below it the sign of V is rounding noise, so
#: which side is outside is left undetermined.
MESH_FLAT_SINE = MESH_DEGENERATE_SINE

#: The unit roundoff of float32, 2**-24: coordinates that are all float32 numbers (STL, glTF,
#: most binary PLY) are taken to be rounded by this much, relative to their size.
FLOAT32_UNIT = 2.0**-24

#: A patch's volume decides its outside only when it exceeds this many times the most that
#: rounding the patch's coordinates (and computing the volume) could move it; see
#: :mod:`mesh_normal.mesh.orientation`. Below that its sign may be noise, and nothing is flipped.
ORIENT_EVIDENCE = 4.0

#: The largest weld tolerance that the report, the fix and their front ends accept, as a
#: fraction of the bounding-box diagonal (``mn.analyse(..., weld=)``, ``--weld``, the API's
#: ``weld``). A weld is for pieces that miss each other by rounding: a float32 step is about
#: 6e-8 of a coordinate, six decimals in an OBJ 1e-6 of a unit; 1e-6 to 1e-4 covers them. Past
#: one percent of the mesh's size a weld no longer repairs rounding but closes real gaps and
#: collapses small features (thin walls, fine detail), which is modelling, not checking.
WELD_LIMIT = 0.01

# Point clouds (mesh_normal.points). Relative again: a cloud in millimetres and the same cloud in
# metres, or moved by 1e8, get the same verdicts.

#: The coordinates are taken to be rounded by half a unit in the last place of the largest
#: one (``EPSILON * max |x|``): at 1e8, 7.5e-9. A neighbourhood whose variance in a direction
#: is at most this factor times that rounding, squared, is flat in that direction to rounding.
POINT_ROUNDING_FACTOR = 16.0

#: A neighbourhood is collinear when its middle eigenvalue is at most this fraction of its
#: largest (plus the rounding above): it is then a line at most 2**-20 (1e-6) times as wide as
#: it is long, and its normal is any direction across the line.
POINT_LINE_RATIO = 2.0**-40

#: A neighbourhood's normal is ambiguous when its two smallest eigenvalues differ by at most
#: this fraction of the largest (plus the rounding above): the flattest direction is then not
#: unique to within about 1e-4 rad (e.g. a corner sampled with three-fold symmetry).
POINT_GAP_RATIO = 2.0**-40

#: The orientation graph links each point to at most this many of its nearest neighbours
#: (CGAL's ``mst_orient_normals`` uses 18; Open3D's consistent tangent plane takes k).
ORIENT_NEIGHBOURS = 12

#: The MST orientation does not carry a sign across two neighbours whose normal lines are
#: further apart than this, in degrees; points reached only that way are left unoriented.
ORIENT_MAX_ANGLE = 60.0

#: A seed decides its component's side only if its normal makes at least this cosine with the
#: reference (outward from the component's centre, or up); a per-point reference (a viewpoint,
#: a direction, stored normals) decides a point only if the cosine is at least this in size.
ORIENT_SEED_COSINE = 0.5

#: A neighbourhood whose surface variation (λ0 / (λ0 + λ1 + λ2), at most 1/3) is over this is
#: far from flat: it reaches across a thin wall or two sheets, a sharp edge, or heavy noise.
#: With k = 30, clean spheres, tori, cylinders and terrain stay under 0.004, a sphere
#: with noise of 1 % of its radius under 0.03, a box's edges reach 0.1 at 1 % of its points,
#: and a slab whose neighbourhoods cross its thickness is over it at 88 %.
POINT_FAR_FROM_FLAT = 0.1
ORIENT_POINT_COSINE = 2.0**-20
