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
