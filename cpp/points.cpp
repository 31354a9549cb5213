// Point clouds: each point's normal from the covariance of its neighbourhood, the orientation
// graph's edges and the signs carried down its spanning tree, and PCD's LZF decompression.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <tuple>

#include <nanobind/stl/tuple.h>

#include "core.hpp"

namespace mesh_normal {

namespace {

using Index = std::int64_t;
using Matrix = double[3][3];

// The estimation codes (the values of mesh_normal.points.estimate.PointStatus).
constexpr Index kOk = 0;
constexpr Index kTooFewNeighbours = 2;
constexpr Index kDuplicates = 3;
constexpr Index kCollinear = 4;
constexpr Index kAmbiguous = 5;

// Jacobi sweeps at most: a 3 x 3 matrix converges quadratically, in 4 or 5.
constexpr int kSweeps = 16;

// The tolerances of the classification, in the frame's units (see estimate.py).
struct Limits {
  double tiny;        // the variance that rounding of the coordinates alone could give
  double line_ratio;  // collinear: the middle eigenvalue within this fraction of the largest
  double gap_ratio;   // ambiguous: the two smallest within this fraction of the largest
};

// One Jacobi rotation that zeroes a[p][q]: a = J^T a J and v = v J. The indices are constants,
// so that the matrices stay in registers.
template <int p, int q>
void rotate(Matrix& a, Matrix& v) {
  const double apq = a[p][q];
  if (apq == 0.0) {
    return;
  }
  const double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
  double t = 0.0;
  if (std::fabs(theta) > 1e150) {  // theta * theta would overflow: t is 1 / (2 theta) to rounding
    t = 0.5 / theta;
  } else {
    t = 1.0 / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
    if (theta < 0.0) {
      t = -t;
    }
  }
  const double c = 1.0 / std::sqrt(t * t + 1.0);
  const double s = t * c;
  for (int k = 0; k < 3; ++k) {
    const double akp = a[k][p];
    const double akq = a[k][q];
    a[k][p] = c * akp - s * akq;
    a[k][q] = s * akp + c * akq;
  }
  for (int k = 0; k < 3; ++k) {
    const double apk = a[p][k];
    const double aqk = a[q][k];
    a[p][k] = c * apk - s * aqk;
    a[q][k] = s * apk + c * aqk;
  }
  a[p][q] = 0.0;
  a[q][p] = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double vkp = v[k][p];
    const double vkq = v[k][q];
    v[k][p] = c * vkp - s * vkq;
    v[k][q] = s * vkp + c * vkq;
  }
}

// Diagonalises the symmetric `a` in place by cyclic Jacobi rotations (accurate for flat, linear
// and isotropic neighbourhoods alike); `v` gets the eigenvectors as columns. The eigenvalues are
// left on the diagonal of `a`, unsorted.
void symmetric_eigen(Matrix& a, Matrix& v) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      v[i][j] = i == j ? 1.0 : 0.0;
    }
  }
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diagonal = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-36 * diagonal || off == 0.0) {
      return;
    }
    rotate<0, 1>(a, v);
    rotate<0, 2>(a, v);
    rotate<1, 2>(a, v);
  }
}

// The covariance of points[neighbours[start:stop]] about its mean (two passes), into `a`.
// Entries that are not rows of the points (a k-d tree's "missing") are skipped; returns how many
// points were used.
Index covariance(const double* points, Index n, const Index* neighbours, Index start, Index stop,
                 Matrix& a, double* mean) {
  Index count = 0;
  double mx = 0.0;
  double my = 0.0;
  double mz = 0.0;
  for (Index e = start; e < stop; ++e) {
    const Index j = neighbours[e];
    if (0 <= j && j < n) {
      mx += points[3 * j];
      my += points[3 * j + 1];
      mz += points[3 * j + 2];
      ++count;
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      a[i][j] = 0.0;
    }
  }
  if (count == 0) {
    return 0;
  }
  const double used = static_cast<double>(count);
  mx /= used;
  my /= used;
  mz /= used;
  mean[0] = mx;
  mean[1] = my;
  mean[2] = mz;
  for (Index e = start; e < stop; ++e) {
    const Index j = neighbours[e];
    if (0 <= j && j < n) {
      const double x = points[3 * j] - mx;
      const double y = points[3 * j + 1] - my;
      const double z = points[3 * j + 2] - mz;
      a[0][0] += x * x;
      a[0][1] += x * y;
      a[0][2] += x * z;
      a[1][1] += y * y;
      a[1][2] += y * z;
      a[2][2] += z * z;
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      a[i][j] /= used;
      a[j][i] = a[i][j];
    }
  }
  return count;
}

// The estimation code of a neighbourhood with sorted eigenvalues low <= middle <= high.
Index classify(double low, double middle, double high, Index count, const Limits& limits) {
  if (count < 3) {
    return kTooFewNeighbours;
  }
  if (high <= limits.tiny) {
    return kDuplicates;
  }
  if (middle <= limits.tiny + limits.line_ratio * high) {
    return kCollinear;
  }
  if (middle - low <= limits.tiny + limits.gap_ratio * high) {
    return kAmbiguous;
  }
  return kOk;
}

struct Row {
  double normal[3];
  double curvature;
  Index used;
  Index status;
  double low;  // the covariance's eigenvalues, sorted
  double middle;
  double high;
  double centre[3];      // the mean of the points used
  double covariance[6];  // xx, xy, xz, yy, yz, zz before the rotations
};

// One neighbourhood's normal from its covariance `a` (overwritten), mean and count: the
// eigenvector of the smallest eigenvalue, its largest component positive (a canonical sign:
// orientation comes later), or zero where the status is not OK; the curvature
// low / (low + middle + high), or 0 where the points coincide or are fewer than three.
Row solve(Matrix& a, const double* mean, Index count, const Limits& limits) {
  const double entries[6] = {a[0][0], a[0][1], a[0][2], a[1][1], a[1][2], a[2][2]};
  Matrix v;
  symmetric_eigen(a, v);
  const double e0 = std::max(a[0][0], 0.0);
  const double e1 = std::max(a[1][1], 0.0);
  const double e2 = std::max(a[2][2], 0.0);
  // The column of the smallest eigenvalue; the other two sorted.
  int column = 2;
  double low = e2;
  double middle = std::min(e0, e1);
  double high = std::max(e0, e1);
  if (e0 <= e1 && e0 <= e2) {
    column = 0;
    low = e0;
    middle = std::min(e1, e2);
    high = std::max(e1, e2);
  } else if (e1 <= e2) {
    column = 1;
    low = e1;
    middle = std::min(e0, e2);
    high = std::max(e0, e2);
  }
  Row row{};
  std::memcpy(row.centre, mean, sizeof row.centre);
  std::memcpy(row.covariance, entries, sizeof entries);
  row.low = low;
  row.middle = middle;
  row.high = high;
  row.used = count;
  row.status = classify(low, middle, high, count, limits);
  const double trace = low + middle + high;
  row.curvature = count >= 3 && high > limits.tiny ? low / trace : 0.0;
  const double x = v[0][column];
  const double y = v[1][column];
  const double z = v[2][column];
  const double ax = std::fabs(x);
  const double ay = std::fabs(y);
  const double az = std::fabs(z);
  const double largest = ax >= ay && ax >= az ? x : (ay >= az ? y : z);
  const double scale =
      row.status != kOk ? 0.0 : (largest > 0 ? 1.0 : -1.0) / std::sqrt(x * x + y * y + z * z);
  row.normal[0] = x * scale + 0.0;  // -0.0 becomes 0.0
  row.normal[1] = y * scale + 0.0;
  row.normal[2] = z * scale + 0.0;
  return row;
}

// The normal of the points neighbours[start:stop] (entries that are not rows are skipped).
Row estimate(const double* points, Index n, const Index* neighbours, Index start, Index stop,
             const Limits& limits) {
  Matrix a;
  double mean[3] = {0.0, 0.0, 0.0};
  const Index count = covariance(points, n, neighbours, start, stop, a, mean);
  return solve(a, mean, count, limits);
}

// The CSR row pointers must run from 0 or more, never backwards, to within the neighbour list.
void check_rows(const Index* indptr, Index rows, Index entries) {
  if (indptr[0] < 0 || indptr[rows] > entries) {
    throw nb::index_error("the neighbour lists' row pointers run outside the neighbour list");
  }
  for (Index r = 0; r < rows; ++r) {
    if (indptr[r + 1] < indptr[r]) {
      throw nb::value_error("the neighbour lists' row pointers run backwards");
    }
  }
}

void neighbourhood_normals(In<double, nb::shape<-1, 3>> points, In<Index, nb::ndim<1>> indptr,
                           In<Index, nb::ndim<1>> neighbours, double tiny, double line_ratio,
                           double gap_ratio, Out<double, nb::shape<-1, 3>> normals,
                           Out<double, nb::ndim<1>> curvature, Out<Index, nb::ndim<1>> used,
                           Out<Index, nb::ndim<1>> status) {
  if (indptr.shape(0) == 0) {
    throw nb::value_error("the neighbour lists need at least one row pointer");
  }
  const Index rows = static_cast<Index>(indptr.shape(0)) - 1;
  for (const std::size_t size :
       {normals.shape(0), curvature.shape(0), used.shape(0), status.shape(0)}) {
    if (static_cast<Index>(size) != rows) {
      throw nb::value_error("every output needs one row per neighbour list");
    }
  }
  const Index* rows_at = indptr.data();
  check_rows(rows_at, rows, static_cast<Index>(neighbours.shape(0)));
  const double* coordinates = points.data();
  const Index n = static_cast<Index>(points.shape(0));
  const Index* lists = neighbours.data();
  const Limits limits{tiny, line_ratio, gap_ratio};
  double* normal_out = normals.data();
  double* curvature_out = curvature.data();
  Index* used_out = used.data();
  Index* status_out = status.data();
  nb::gil_scoped_release release;
  parallel_for(rows, 256, [&](Index begin, Index end) {
    for (Index r = begin; r < end; ++r) {
      const Row row = estimate(coordinates, n, lists, rows_at[r], rows_at[r + 1], limits);
      std::memcpy(normal_out + 3 * r, row.normal, sizeof row.normal);
      curvature_out[r] = row.curvature;
      used_out[r] = row.used;
      status_out[r] = row.status;
    }
  });
}

double dot(const double* p, const double* q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; }

// The spread of a PCA normal's direction from noise alone: the variance of its tilt towards each
// other eigenvector is low * other / (count * (other - low)^2) (the first-order perturbation of
// the eigenvector); the sum of both, square-rooted.
double tilt(const Row& row) {
  const double count = static_cast<double>(row.used);
  const double a = row.middle - row.low;
  const double b = row.high - row.low;
  if (a <= 0.0 || b <= 0.0) {
    return 1.0;
  }
  return std::sqrt(row.low / count * (row.middle / (a * a) + row.high / (b * b)));
}

// One row of multiscale_normals: the fits over the first scales[c] neighbours, and the largest
// scale whose normal agrees with every smaller scale's to within `threshold` times the sum of
// their spreads (Lepski's rule: a larger scale is taken while its change is explained by noise;
// where curvature or an edge bends it, the change outgrows the spreads and the scale stops).
Row multiscale(const double* points, Index n, const Index* list, Index start, Index stop,
               const Index* scales, Index count, const Limits& limits, double threshold,
               double planar, Row& smallest, Row& largest, double& spread_out) {
  constexpr Index kMostScales = 16;
  Row fits[kMostScales];
  double spread[kMostScales];
  Index fitted = 0;
  for (Index c = 0; c < count && fitted < kMostScales; ++c) {
    const Index end = std::min(stop, start + scales[c]);
    fits[fitted] = estimate(points, n, list, start, end, limits);
    spread[fitted] = tilt(fits[fitted]);
    ++fitted;
    if (end == stop) {
      break;
    }
  }
  Index chosen = -1;
  for (Index c = 0; c < fitted; ++c) {
    if (fits[c].status != kOk) {
      if (chosen < 0) {
        continue;
      }
      break;
    }
    bool agrees = true;
    for (Index t = 0; t < c && agrees; ++t) {
      // A fit whose two smallest eigenvalues are within `planar` of each other has no plane
      // to hold a larger scale to (noise outgrows it): its spread's first order fails there.
      if (fits[t].status != kOk || fits[t].low > planar * fits[t].middle) {
        continue;
      }
      const double cosine = std::min(1.0, std::fabs(dot(fits[t].normal, fits[c].normal)));
      const double sine = std::sqrt(1.0 - cosine * cosine);
      // More points spread a normal less: a larger scale that spreads more owes it to a
      // curve or an edge it reaches, not to noise, and its spread says nothing.
      agrees = sine <= threshold * (spread[t] + std::min(spread[t], spread[c]));
    }
    if (!agrees) {
      break;
    }
    chosen = c;
  }
  smallest = fits[0];
  largest = fits[fitted - 1];
  spread_out = chosen >= 0 ? spread[chosen] : 1.0;
  // With no scale OK, the largest fit says why (too few, duplicates, collinear, ambiguous).
  return chosen >= 0 ? fits[chosen] : fits[fitted - 1];
}

void multiscale_normals(In<double, nb::shape<-1, 3>> points, In<Index, nb::ndim<2>> neighbours,
                        In<Index, nb::ndim<1>> scales, double tiny, double line_ratio,
                        double gap_ratio, double threshold, double planar,
                        Out<double, nb::shape<-1, 3>> normals, Out<double, nb::ndim<1>> curvature,
                        Out<Index, nb::ndim<1>> used, Out<Index, nb::ndim<1>> status,
                        Out<double, nb::ndim<1>> residual, Out<double, nb::ndim<1>> spread,
                        Out<double, nb::shape<-1, 3>> planes, Out<double, nb::shape<-1, 3>> centres,
                        Out<double, nb::ndim<1>> roughness, Out<double, nb::shape<-1, 10>> moments) {
  const Index rows = static_cast<Index>(neighbours.shape(0));
  const Index columns = static_cast<Index>(neighbours.shape(1));
  for (const std::size_t size : {normals.shape(0), curvature.shape(0), used.shape(0),
                                 status.shape(0), residual.shape(0), spread.shape(0),
                                 planes.shape(0), centres.shape(0), roughness.shape(0),
                                 moments.shape(0)}) {
    if (static_cast<Index>(size) != rows) {
      throw nb::value_error("every output needs one row per neighbour list");
    }
  }
  const Index count = static_cast<Index>(scales.shape(0));
  const Index* sizes = scales.data();
  if (count == 0 || count > 16) {
    throw nb::value_error("give from 1 to 16 scales");
  }
  for (Index c = 0; c < count; ++c) {
    if (sizes[c] < 1 || (c > 0 && sizes[c] <= sizes[c - 1])) {
      throw nb::value_error("the scales must be positive and increasing");
    }
  }
  const double* coordinates = points.data();
  const Index n = static_cast<Index>(points.shape(0));
  const Index* lists = neighbours.data();
  const Limits limits{tiny, line_ratio, gap_ratio};
  double* normal_out = normals.data();
  double* plane_out = planes.data();
  double* centre_out = centres.data();
  double* roughness_out = roughness.data();
  double* moment_out = moments.data();
  double* curvature_out = curvature.data();
  double* residual_out = residual.data();
  double* spread_out = spread.data();
  Index* used_out = used.data();
  Index* status_out = status.data();
  nb::gil_scoped_release release;
  parallel_for(rows, 64, [&](Index begin, Index end) {
    for (Index r = begin; r < end; ++r) {
      Row smallest;
      Row largest;
      const Row row = multiscale(coordinates, n, lists, r * columns, (r + 1) * columns, sizes,
                                 count, limits, threshold, planar, smallest, largest,
                                 spread_out[r]);
      double* moment = moment_out + 10 * r;
      moment[0] = static_cast<double>(largest.used);
      std::memcpy(moment + 1, largest.centre, sizeof largest.centre);
      for (int e = 0; e < 6; ++e) {
        moment[4 + e] = largest.covariance[e] * moment[0];
      }
      std::memcpy(normal_out + 3 * r, row.normal, sizeof row.normal);
      curvature_out[r] = row.curvature;
      residual_out[r] = std::sqrt(row.low);
      std::memcpy(plane_out + 3 * r, smallest.normal, sizeof smallest.normal);
      std::memcpy(centre_out + 3 * r, smallest.centre, sizeof smallest.centre);
      roughness_out[r] = std::sqrt(smallest.low);
      used_out[r] = row.used;
      status_out[r] = row.status;
    }
  });
}

// A neighbourhood's moments, as rows of 10: count, mean, scatter (xx, xy, xz, yy, yz, zz; the
// sum of the outer products of the steps from the mean). Two merge by Chan et al.'s update.
void merge(double* into, const double* other) {
  const double a = into[0];
  const double b = other[0];
  const double total = a + b;
  if (b == 0.0) {
    return;
  }
  const double d[3] = {other[1] - into[1], other[2] - into[2], other[3] - into[3]};
  const double share = b / total;
  const double product = a * share;  // a b / (a + b)
  into[0] = total;
  for (int e = 0; e < 3; ++e) {
    into[1 + e] += d[e] * share;
  }
  into[4] += other[4] + product * d[0] * d[0];
  into[5] += other[5] + product * d[0] * d[1];
  into[6] += other[6] + product * d[0] * d[2];
  into[7] += other[7] + product * d[1] * d[1];
  into[8] += other[8] + product * d[1] * d[2];
  into[9] += other[9] + product * d[2] * d[2];
}

// Each point's moments merged with its neighbours': the neighbourhoods of the neighbours
// together, a point counted once for each that holds it (a smooth, wider neighbourhood at the
// cost of one pass).
void widened_moments(In<double, nb::shape<-1, 10>> moments,
                     In<std::int32_t, nb::ndim<2>> neighbours, Out<double, nb::shape<-1, 10>> out) {
  const Index n = static_cast<Index>(moments.shape(0));
  const Index columns = static_cast<Index>(neighbours.shape(1));
  if (static_cast<Index>(neighbours.shape(0)) != n || static_cast<Index>(out.shape(0)) != n) {
    throw nb::value_error("the moments, neighbours and output need one row per point");
  }
  const double* in = moments.data();
  const std::int32_t* lists = neighbours.data();
  double* result = out.data();
  nb::gil_scoped_release release;
  parallel_for(n, 256, [&](Index begin, Index end) {
    for (Index i = begin; i < end; ++i) {
      double sum[10];
      std::memcpy(sum, in + 10 * i, sizeof sum);
      for (Index c = 0; c < columns; ++c) {
        const Index j = lists[i * columns + c];
        if (0 <= j && j < n && j != i) {
          merge(sum, in + 10 * j);
        }
      }
      std::memcpy(result + 10 * i, sum, sizeof sum);
    }
  });
}

// The normal of each row of moments, as neighbourhood_normals, its residual and its spread from
// noise taken as if from `effective` points (a widened neighbourhood counts points several
// times: its count overstates what noise averages out).
void moment_normals(In<double, nb::shape<-1, 10>> moments, double effective, double tiny,
                    double line_ratio, double gap_ratio, Out<double, nb::shape<-1, 3>> normals,
                    Out<double, nb::ndim<1>> curvature, Out<double, nb::ndim<1>> residual,
                    Out<double, nb::ndim<1>> spread, Out<Index, nb::ndim<1>> status) {
  const Index n = static_cast<Index>(moments.shape(0));
  for (const std::size_t size : {normals.shape(0), curvature.shape(0), residual.shape(0),
                                 spread.shape(0), status.shape(0)}) {
    if (static_cast<Index>(size) != n) {
      throw nb::value_error("every output needs one row per row of moments");
    }
  }
  const double* in = moments.data();
  const Limits limits{tiny, line_ratio, gap_ratio};
  const double most = std::isfinite(effective) && effective > 0.0 ? effective : 0.0;
  double* normal_out = normals.data();
  double* curvature_out = curvature.data();
  double* residual_out = residual.data();
  double* spread_out = spread.data();
  Index* status_out = status.data();
  nb::gil_scoped_release release;
  parallel_for(n, 256, [&](Index begin, Index end) {
    for (Index r = begin; r < end; ++r) {
      const double* m = in + 10 * r;
      // A count that is not a count (negative, NaN, past any cloud) is no points.
      const double held = std::isfinite(m[0]) && m[0] >= 1.0 ? std::min(m[0], 1e15) : 0.0;
      const double count = held > 0.0 ? held : 1.0;
      Matrix a = {{m[4] / count, m[5] / count, m[6] / count},
                  {m[5] / count, m[7] / count, m[8] / count},
                  {m[6] / count, m[8] / count, m[9] / count}};
      Row row = solve(a, m + 1, static_cast<Index>(held), limits);
      std::memcpy(normal_out + 3 * r, row.normal, sizeof row.normal);
      curvature_out[r] = row.curvature;
      residual_out[r] = std::sqrt(row.low);
      row.used = static_cast<Index>(std::min(most, held));
      spread_out[r] = tilt(row);
      status_out[r] = row.status;
    }
  });
}

// Points near a sharp edge or corner. A fit across an edge blends both sides; the plane the
// point lies on holds more of its neighbours than any other plane through it. Each neighbour's
// smallest-scale fit (its normal through its centre) is a candidate plane; a candidate counts
// the neighbours within `factor` times the neighbourhood's noise (the lower quartile of their
// fits' residuals: most fits are of one side only, even at an edge; at least `floor`) of it,
// and must hold the point itself. Where the best candidate leaves out more than `keep` of the
// neighbours, the point is near a feature: its normal is refitted to the best candidate's
// inliers and taken where the point's fit is over `blend` times less flat (in residual) and
// turns by a sine over `turn` and over three times the fit's spread from noise. `normals` is written where `sharp` is set.
void sharp_normals(In<double, nb::shape<-1, 3>> points, In<std::int32_t, nb::ndim<2>> neighbours,
                   In<double, nb::shape<-1, 3>> fits, In<double, nb::ndim<1>> residual,
                   In<double, nb::ndim<1>> spread, In<Index, nb::ndim<1>> status,
                   In<double, nb::shape<-1, 3>> planes, In<double, nb::shape<-1, 3>> centres,
                   double tiny, double line_ratio, double gap_ratio, double factor, double keep,
                   double blend, double turn, double floor, Out<double, nb::shape<-1, 3>> normals,
                   Out<bool, nb::ndim<1>> sharp) {
  const Index n = static_cast<Index>(points.shape(0));
  const Index columns = static_cast<Index>(neighbours.shape(1));
  for (const std::size_t size :
       {neighbours.shape(0), fits.shape(0), residual.shape(0), spread.shape(0), status.shape(0),
        planes.shape(0), centres.shape(0), normals.shape(0), sharp.shape(0)}) {
    if (static_cast<Index>(size) != n) {
      throw nb::value_error("the points, neighbours, fits and outputs need one row per point");
    }
  }
  constexpr Index kMostColumns = 64;
  if (columns > kMostColumns) {
    throw nb::value_error("give at most 64 neighbours a point");
  }
  const double* xyz = points.data();
  const std::int32_t* lists = neighbours.data();
  const double* fitted = fits.data();
  const double* residuals = residual.data();
  const double* spreads = spread.data();
  const Index* codes = status.data();
  const double* flat = planes.data();
  const double* middle = centres.data();
  double* out = normals.data();
  bool* marked = sharp.data();
  const Limits limits{tiny, line_ratio, gap_ratio};
  nb::gil_scoped_release release;
  parallel_for(n, 128, [&](Index begin, Index end) {
    Index near[kMostColumns + 1];
    Index inliers[kMostColumns + 1];
    double noise[kMostColumns + 1];
    for (Index i = begin; i < end; ++i) {
      marked[i] = false;
      if (codes[i] != kOk) {
        continue;
      }
      // The neighbourhood: the point first, then its neighbours that are rows.
      Index count = 0;
      near[count++] = i;
      for (Index c = 0; c < columns; ++c) {
        const Index j = lists[i * columns + c];
        if (0 <= j && j < n && j != i) {
          near[count++] = j;
        }
      }
      Index fitted_count = 0;
      for (Index c = 0; c < count; ++c) {
        if (codes[near[c]] == kOk) {
          noise[fitted_count++] = residuals[near[c]];
        }
      }
      if (count < 6) {
        continue;
      }
      std::nth_element(noise, noise + fitted_count / 4, noise + fitted_count);
      const double tolerance = factor * std::max(noise[fitted_count / 4], floor);
      // Whether point q lies on the plane of candidate j.
      const auto on_plane = [&](Index j, Index q) {
        const double* centre = middle + 3 * j;
        const double* at = xyz + 3 * q;
        const double step[3] = {at[0] - centre[0], at[1] - centre[1], at[2] - centre[2]};
        return std::fabs(dot(flat + 3 * j, step)) <= tolerance;
      };
      Index best = -1;
      Index most = 0;
      for (Index c = 0; c < count; ++c) {
        if (dot(flat + 3 * near[c], flat + 3 * near[c]) == 0.0 || !on_plane(near[c], i)) {
          continue;  // no plane, or not the point's
        }
        Index held = 0;
        for (Index e = 0; e < count; ++e) {
          held += on_plane(near[c], near[e]) ? 1 : 0;
        }
        if (held > most) {
          best = near[c];
          most = held;
        }
      }
      if (best < 0 || static_cast<double>(most) >= keep * static_cast<double>(count)) {
        continue;
      }
      Index held = 0;
      for (Index e = 0; e < count; ++e) {
        if (on_plane(best, near[e])) {
          inliers[held++] = near[e];
        }
      }
      const Row refit = estimate(xyz, n, inliers, 0, held, limits);
      // A side holds a quarter of the neighbours at least (as at a corner), spread over an
      // area, not along a line; a thin band of inliers can turn the refit across the band.
      // On a curved surface the band is no flatter than the point's own fit: only a fit that
      // blends two sides is much less flat than the side's.
      if (refit.status != kOk || 4 * held < count || refit.middle < 0.05 * refit.high ||
          std::fabs(dot(refit.normal, flat + 3 * best)) < std::cos(0.3) ||
          residuals[i] <= blend * std::sqrt(refit.low)) {
        continue;
      }
      const double cosine = std::min(1.0, std::fabs(dot(fitted + 3 * i, refit.normal)));
      if (std::sqrt(1.0 - cosine * cosine) > std::max(turn, 3.0 * spreads[i])) {
        std::memcpy(out + 3 * i, refit.normal, 3 * sizeof(double));
        marked[i] = true;
      }
    }
  });
}

// Whether `value` is in row `row` of the graph.
bool listed(const std::int32_t* graph, Index columns, Index row, std::int32_t value) {
  const std::int32_t* list = graph + row * columns;
  return std::find(list, list + columns, value) != list + columns;
}

using Edges = std::tuple<nb::ndarray<nb::numpy, std::int32_t>, nb::ndarray<nb::numpy, std::int32_t>,
                         nb::ndarray<nb::numpy, double>>;

// The edges of the neighbour graph between valid points, each once, in the order of the graph's
// rows: weight 1 - |n_i . n_j| + floor. With sine_limit below 1, an edge is left out where the
// step between the points leaves either tangent plane by a sine over it, and otherwise weighs
// that sine more.
Edges graph_edges(In<double, nb::shape<-1, 3>> points, In<double, nb::shape<-1, 3>> normals,
                  In<bool, nb::ndim<1>> valid, In<std::int32_t, nb::ndim<2>> graph, double floor,
                  double sine_limit) {
  const Index n = static_cast<Index>(points.shape(0));
  if (static_cast<Index>(normals.shape(0)) != n || static_cast<Index>(valid.shape(0)) != n ||
      static_cast<Index>(graph.shape(0)) != n) {
    throw nb::value_error("the points, normals, valid flags and graph need one row per point");
  }
  const Index columns = static_cast<Index>(graph.shape(1));
  const std::int32_t* links = graph.data();
  for (Index e = 0; e < n * columns; ++e) {
    if (links[e] >= n) {
      throw nb::index_error("a neighbour in the orientation graph is not one of the points");
    }
  }
  const double* xyz = points.data();
  const double* lines = normals.data();
  const bool* usable = valid.data();
  const auto most = static_cast<std::size_t>(n * columns);
  std::unique_ptr<std::int32_t[]> rows(new std::int32_t[most]);
  std::unique_ptr<std::int32_t[]> cols(new std::int32_t[most]);
  std::unique_ptr<double[]> weights(new double[most]);
  Index count = 0;
  {
    nb::gil_scoped_release release;
    for (Index i = 0; i < n; ++i) {
      if (!usable[i]) {
        continue;
      }
      const double* ni = lines + 3 * i;
      for (Index c = 0; c < columns; ++c) {
        const std::int32_t j = links[i * columns + c];
        if (j < 0 || j == i || !usable[j] ||
            (j < i && listed(links, columns, j, static_cast<std::int32_t>(i)))) {
          continue;  // (j, i) was written from j's list
        }
        const double* nj = lines + 3 * static_cast<Index>(j);
        double weight = 1.0 - std::fabs(dot(ni, nj)) + floor;
        if (sine_limit < 1.0) {
          const double* pi = xyz + 3 * i;
          const double* pj = xyz + 3 * static_cast<Index>(j);
          const double step[3] = {pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]};
          const double length = std::sqrt(dot(step, step));
          const double sine = length == 0.0 ? 0.0
                                             : std::max(std::fabs(dot(step, ni)),
                                                        std::fabs(dot(step, nj))) /
                                                   length;
          if (sine > sine_limit) {
            continue;
          }
          weight += sine;
        }
        rows[count] = static_cast<std::int32_t>(i);
        cols[count] = j;
        weights[count] = weight;
        ++count;
      }
    }
  }
  const auto written = static_cast<std::size_t>(count);
  return {owned(std::move(rows), written), owned(std::move(cols), written),
          owned(std::move(weights), written)};
}

using Flags = std::tuple<nb::ndarray<nb::numpy, bool>, nb::ndarray<nb::numpy, bool>>;

// Signs carried from each tree's root down a breadth-first `order`: `flip` and `cut` (a point
// is cut, left unoriented and not flipped, when the path from its root crosses a sharp edge).
Flags propagate_signs(In<std::int32_t, nb::ndim<1>> order, In<std::int32_t, nb::ndim<1>> parent,
                      In<bool, nb::ndim<1>> agrees, In<bool, nb::ndim<1>> sharp,
                      In<bool, nb::ndim<1>> seed_flip) {
  const Index n = static_cast<Index>(parent.shape(0));
  if (static_cast<Index>(agrees.shape(0)) != n || static_cast<Index>(sharp.shape(0)) != n ||
      static_cast<Index>(seed_flip.shape(0)) != n) {
    throw nb::value_error("the parents and the flags need one row per point");
  }
  const std::int32_t* walk = order.data();
  const std::int32_t* up = parent.data();
  const Index steps = static_cast<Index>(order.shape(0));
  for (Index s = 0; s < steps; ++s) {
    if (walk[s] < 0 || walk[s] >= n) {
      throw nb::index_error("a point in the tree's order is not one of the points");
    }
  }
  for (Index i = 0; i < n; ++i) {
    if (up[i] >= n) {
      throw nb::index_error("a parent in the tree is not one of the points");
    }
  }
  const bool* agree = agrees.data();
  const bool* steep = sharp.data();
  const bool* seeded = seed_flip.data();
  std::unique_ptr<bool[]> flip(new bool[static_cast<std::size_t>(n)]());
  std::unique_ptr<bool[]> cut(new bool[static_cast<std::size_t>(n)]());
  {
    nb::gil_scoped_release release;
    for (Index s = 0; s < steps; ++s) {
      const Index i = walk[s];
      const std::int32_t p = up[i];
      if (p < 0) {
        flip[i] = seeded[i];
      } else {
        cut[i] = steep[i] || cut[p];
        flip[i] = (flip[p] != !agree[i]) && !cut[i];
      }
    }
  }
  return {owned(std::move(flip), static_cast<std::size_t>(n)),
          owned(std::move(cut), static_cast<std::size_t>(n))};
}

// What lzf returns for data that would write past the end of `out`, and for data that break
// the format.
constexpr Index kPastTheEnd = -2;
constexpr Index kBroken = -1;

// Unpacks LZF (Marc Lehmann's format) `source` into `out`: the bytes written, kBroken where the
// data break the format, kPastTheEnd where they would write past the end of `out`. Every offset
// and length read from the data is checked before it is used.
Index unpack_lzf(const std::uint8_t* source, Index end, std::uint8_t* out, Index size) {
  Index i = 0;
  Index o = 0;
  while (i < end) {
    const Index control = source[i];
    ++i;
    if (control < 32) {  // a literal run of control + 1 bytes
      const Index length = control + 1;
      if (o + length > size) {
        return kPastTheEnd;
      }
      if (i + length > end) {
        return kBroken;
      }
      std::memcpy(out + o, source + i, static_cast<std::size_t>(length));
      i += length;
      o += length;
      continue;
    }
    Index length = control >> 5;
    if (length == 7) {
      if (i >= end) {
        return kBroken;
      }
      length += source[i];
      ++i;
    }
    if (i >= end) {
      return kBroken;
    }
    const Index reference = o - ((control & 31) << 8) - source[i] - 1;
    ++i;
    length += 2;
    if (o + length > size) {
      return kPastTheEnd;
    }
    if (reference < 0) {
      return kBroken;
    }
    for (Index k = 0; k < length; ++k) {  // byte by byte: an overlapping copy repeats what it wrote
      out[o + k] = out[reference + k];
    }
    o += length;
  }
  return o;
}

Index lzf(In<std::uint8_t, nb::ndim<1>> source, Out<std::uint8_t, nb::ndim<1>> out) {
  const std::uint8_t* packed = source.data();
  const Index end = static_cast<Index>(source.shape(0));
  std::uint8_t* unpacked = out.data();
  const Index size = static_cast<Index>(out.shape(0));
  nb::gil_scoped_release release;
  return unpack_lzf(packed, end, unpacked, size);
}

}  // namespace

void bind_points(nb::module_& m) {
  m.def("neighbourhood_normals", &neighbourhood_normals, nb::arg("points").noconvert(),
        nb::arg("indptr").noconvert(), nb::arg("neighbours").noconvert(), nb::arg("tiny"),
        nb::arg("line_ratio"), nb::arg("gap_ratio"), nb::arg("normals").noconvert(),
        nb::arg("curvature").noconvert(), nb::arg("used").noconvert(),
        nb::arg("status").noconvert(),
        "Row r of the outputs from the points neighbours[indptr[r]:indptr[r + 1]] (entries that "
        "are not rows of the points are skipped): the unit normal with its largest component "
        "positive (zero unless the status is 0), the curvature, how many points were used and "
        "the status code.");
  m.def("multiscale_normals", &multiscale_normals, nb::arg("points").noconvert(),
        nb::arg("neighbours").noconvert(), nb::arg("scales").noconvert(), nb::arg("tiny"),
        nb::arg("line_ratio"), nb::arg("gap_ratio"), nb::arg("threshold"), nb::arg("planar"),
        nb::arg("normals").noconvert(), nb::arg("curvature").noconvert(),
        nb::arg("used").noconvert(), nb::arg("status").noconvert(),
        nb::arg("residual").noconvert(), nb::arg("spread").noconvert(),
        nb::arg("planes").noconvert(), nb::arg("centres").noconvert(),
        nb::arg("roughness").noconvert(), nb::arg("moments").noconvert(),
        "Row r of the outputs from the fits over the first scales[c] entries of neighbours[r] "
        "(nearest first; entries that are not rows of the points are skipped), at the largest "
        "scale whose normal agrees with every smaller one's (that are planar: smallest eigenvalue "
        "at most planar times the middle one) to within threshold times their spreads from "
        "noise: as neighbourhood_normals, its residual (the root of the smallest eigenvalue) and "
        "spread from noise; the smallest scale's normal (zero where it has none), centre and "
        "residual; and the largest scale's moments (count, mean, scatter xx xy xz yy yz zz).");
  m.def("widened_moments", &widened_moments, nb::arg("moments").noconvert(),
        nb::arg("neighbours").noconvert(), nb::arg("out").noconvert(),
        "Each row of moments (count, mean, scatter xx xy xz yy yz zz) merged with those of its "
        "neighbours (entries that are not rows are skipped).");
  m.def("moment_normals", &moment_normals, nb::arg("moments").noconvert(), nb::arg("effective"),
        nb::arg("tiny"), nb::arg("line_ratio"), nb::arg("gap_ratio"),
        nb::arg("normals").noconvert(), nb::arg("curvature").noconvert(),
        nb::arg("residual").noconvert(), nb::arg("spread").noconvert(),
        nb::arg("status").noconvert(),
        "The normal of each row of moments as neighbourhood_normals, its residual, and its "
        "spread from noise as if from at most `effective` points.");
  m.def("sharp_normals", &sharp_normals, nb::arg("points").noconvert(),
        nb::arg("neighbours").noconvert(), nb::arg("fits").noconvert(),
        nb::arg("residual").noconvert(), nb::arg("spread").noconvert(),
        nb::arg("status").noconvert(), nb::arg("planes").noconvert(),
        nb::arg("centres").noconvert(), nb::arg("tiny"), nb::arg("line_ratio"),
        nb::arg("gap_ratio"), nb::arg("factor"), nb::arg("keep"), nb::arg("blend"), nb::arg("turn"),
        nb::arg("floor"), nb::arg("normals").noconvert(), nb::arg("sharp").noconvert(),
        "Near sharp edges: the plane through a point that holds the most of its neighbours "
        "(within factor times their fits' residuals' lower quartile), among its neighbours' "
        "planes (normals through centres; a zero normal: none); where it leaves out more than "
        "keep of them, the normal refitted to those it holds, taken where the fit's residual is "
        "over blend times the refit's and it turns the fit by a sine over turn and three times "
        "its spread; sharp marks them.");
  m.def("graph_edges", &graph_edges, nb::arg("points").noconvert(), nb::arg("normals").noconvert(),
        nb::arg("valid").noconvert(), nb::arg("graph").noconvert(), nb::arg("floor"),
        nb::arg("sine_limit"),
        "The edges of the neighbour graph between valid points, each once: rows, columns and "
        "weights 1 - |n_i . n_j| + floor; with sine_limit below 1, edges that leave a tangent "
        "plane by a sine over it are left out and the others weigh that sine more.");
  m.def("propagate_signs", &propagate_signs, nb::arg("order").noconvert(),
        nb::arg("parent").noconvert(), nb::arg("agrees").noconvert(),
        nb::arg("sharp").noconvert(), nb::arg("seed_flip").noconvert(),
        "Signs carried from each tree's root down a breadth-first order: (flip, cut).");
  m.def("lzf", &lzf, nb::arg("source").noconvert(), nb::arg("out").noconvert(),
        "Unpack LZF source into out: the bytes written, -1 where the data break the format, -2 "
        "where they would write past the end of out.");
}

}  // namespace mesh_normal
