"""The array and vector types of the library, in one place."""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

FloatArray: TypeAlias = NDArray[np.float64]
IndexArray: TypeAlias = NDArray[np.intp]
BoolArray: TypeAlias = NDArray[np.bool_]
ByteArray: TypeAlias = NDArray[np.uint8]
#: 0 or 1 a face (a face's parity to its patch's first face): one byte each.
ParityArray: TypeAlias = NDArray[np.int8]
#: A point or direction as three floats, the way the compiled kernels pass them.
Vector: TypeAlias = tuple[float, float, float]
#: The three edges of a face, B - A, C - B, A - C.
Edges: TypeAlias = tuple[Vector, Vector, Vector]
