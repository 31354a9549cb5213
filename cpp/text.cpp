// Text and binary parsing: an OBJ chunk's lines, numbers and face corners read from its bytes,
// and a binary PLY's integer lists read from its records.
//
// The OBJ scan reads what it can certify and declines the rest (returns None): the Python
// reader then reads that chunk itself, so every form, note and error message is the Python
// reader's. A number is certified when it is `[+-]digits[.digits][e[+-]digits]`, which Python's
// float() reads as std::from_chars does: both are correctly rounded, so the bits agree.
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>

#include <charconv>
#include <cstring>
#include <limits>
#include <optional>
#include <system_error>

#include "core.hpp"

namespace mesh_normal {

namespace {

// What the scan says of a line (the Python reader's kinds; UNKNOWN is left to Python).
constexpr std::int8_t UNKNOWN = -1, IGNORE = 0, VERTEX = 1, NORMAL = 2, TEXTURE = 3, FACE = 4;

constexpr bool is_digit(std::uint8_t byte) { return byte >= '0' && byte <= '9'; }
constexpr bool is_blank(std::uint8_t byte) { return byte == ' ' || byte == '\t'; }

template <typename T>
using Array = nb::ndarray<nb::numpy, T>;

// A NumPy array that owns a vector's memory (no copy).
template <typename T>
Array<T> array_of(std::vector<T>&& values, std::size_t columns = 0) {
  auto* held = new std::vector<T>(std::move(values));
  nb::capsule owner(held, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
  const std::size_t count = columns ? held->size() / columns : held->size();
  if (columns == 0) {
    return Array<T>(held->data(), {count}, owner);
  }
  return Array<T>(held->data(), {count, columns}, owner);
}

// The decimal token at data[start, end) up to a space or tab: its value, and the byte after
// it; false when it is no decimal of the certified form.
bool decimal(const std::uint8_t* data, std::int64_t start, std::int64_t end, std::int64_t& stop,
             double& value) {
  std::int64_t i = start;
  const bool negative = i < end && data[i] == '-';
  if (i < end && (data[i] == '+' || data[i] == '-')) {
    ++i;
  }
  const std::int64_t digits_start = i;
  // Where the first significant digit stands against the point, to tell an overflow from an
  // underflow when from_chars finds the value out of range.
  std::int64_t magnitude = 0;
  bool seen = false, significant = false;
  for (; i < end && is_digit(data[i]); ++i) {
    seen = true;
    significant = significant || data[i] != '0';
    magnitude += significant ? 1 : 0;
  }
  if (i < end && data[i] == '.') {
    for (++i; i < end && is_digit(data[i]); ++i) {
      seen = true;
      significant = significant || data[i] != '0';
      magnitude -= significant ? 0 : 1;
    }
  }
  if (!seen) {
    return false;
  }
  if (i < end && (data[i] == 'e' || data[i] == 'E')) {
    ++i;
    const bool minus = i < end && data[i] == '-';
    if (i < end && (data[i] == '+' || data[i] == '-')) {
      ++i;
    }
    if (i >= end || !is_digit(data[i])) {
      return false;
    }
    std::int64_t power = 0;
    for (; i < end && is_digit(data[i]); ++i) {
      power = power < 100000 ? power * 10 + (data[i] - '0') : power;
    }
    magnitude += minus ? -power : power;
  }
  if (i < end && !is_blank(data[i])) {
    return false;
  }
  const char* first = reinterpret_cast<const char*>(data + digits_start);
  const char* last = reinterpret_cast<const char*>(data + i);
  double read = 0.0;
  const auto [ptr, error] = std::from_chars(first, last, read, std::chars_format::general);
  if (ptr != last || (error != std::errc() && error != std::errc::result_out_of_range)) {
    return false;
  }
  if (error == std::errc::result_out_of_range) {
    // float() gives infinity past the largest double and zero below half the smallest.
    read = magnitude > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  }
  stop = i;
  value = negative ? -read : read;
  return true;
}

// The integer at data[start, end) (`[+-]digits`, at most 18 of them); false when there is none.
bool integer(const std::uint8_t* data, std::int64_t start, std::int64_t end, std::int64_t& stop,
             std::int64_t& value) {
  std::int64_t i = start;
  const bool negative = i < end && data[i] == '-';
  if (i < end && (data[i] == '+' || data[i] == '-')) {
    ++i;
  }
  std::int64_t read = 0, digits = 0;
  for (; i < end && is_digit(data[i]) && digits <= 18; ++i, ++digits) {
    read = digits < 18 ? read * 10 + (data[i] - '0') : read;  // 19 digits decline: no overflow
  }
  if (digits == 0 || digits > 18) {
    return false;
  }
  stop = i;
  value = negative ? -read : read;
  return true;
}

// What the scan of one OBJ chunk finds.
struct ObjLines {
  std::vector<std::int8_t> kinds;
  std::vector<double> vertices, colors, normals;
  std::vector<std::int64_t> vertex_ids, normal_ids, counts;
  std::vector<std::int64_t> unknown;  // row, start, end of each line left to Python
  bool all_colors = true, all_normals = true;
  const std::uint8_t* data = nullptr;
};

// The numbers of a `v` or `vn` line from `i`: the first three kept (and, for `v`, the colours
// of a line of exactly six); false when one is no certified decimal or there are fewer than 3.
bool numbers_line(ObjLines& out, std::int64_t i, std::int64_t end, bool vertex) {
  double values[6] = {0, 0, 0, 0, 0, 0};
  std::int64_t width = 0;
  for (;;) {
    while (i < end && is_blank(out.data[i])) {
      ++i;
    }
    if (i >= end) {
      break;
    }
    double value = 0.0;
    if (!decimal(out.data, i, end, i, value)) {
      return false;
    }
    if (width < 6) {
      values[width] = value;
    }
    ++width;
  }
  if (width < 3) {
    return false;
  }
  auto& target = vertex ? out.vertices : out.normals;
  target.insert(target.end(), values, values + 3);
  if (vertex) {
    out.all_colors = out.all_colors && width == 6;
    if (out.all_colors) {
      out.colors.insert(out.colors.end(), values + 3, values + 6);
    }
  }
  return true;
}

// One face corner at `i` (`v`, `v/vt`, `v//vn`, `v/vt/vn`, `v/`, `v//`): false when it is not.
bool corner(ObjLines& out, std::int64_t& i, std::int64_t end) {
  const std::uint8_t* data = out.data;
  std::int64_t vertex = 0, normal = 0, texture = 0;
  bool has_normal = false;
  if (!integer(data, i, end, i, vertex)) {
    return false;
  }
  if (i < end && data[i] == '/') {
    ++i;
    if (i < end && data[i] != '/' && !is_blank(data[i]) && !integer(data, i, end, i, texture)) {
      return false;
    }
    if (i < end && data[i] == '/') {
      ++i;
      if (i < end && !is_blank(data[i]) && data[i] != '#') {
        if (!integer(data, i, end, i, normal)) {
          return false;
        }
        has_normal = true;
      }
    }
  }
  if (i < end && !is_blank(data[i]) && data[i] != '#') {
    return false;
  }
  out.all_normals = out.all_normals && has_normal;
  out.vertex_ids.push_back(vertex);
  out.normal_ids.push_back(normal);
  return true;
}

// The corners of an `f` line from `i`, up to its end or a comment.
bool face_line(ObjLines& out, std::int64_t i, std::int64_t end) {
  std::int64_t count = 0;
  for (;;) {
    while (i < end && is_blank(out.data[i])) {
      ++i;
    }
    if (i >= end || out.data[i] == '#') {
      break;
    }
    if (!corner(out, i, end)) {
      return false;
    }
    ++count;
  }
  out.counts.push_back(count);
  return true;
}

// The kind of the line data[position, end), its numbers or corners read; false to decline.
bool obj_line(ObjLines& out, std::int64_t position, std::int64_t end) {
  const std::uint8_t* data = out.data;
  const std::uint8_t first = end > position ? data[position] : 0;
  const std::uint8_t second = end > position + 1 ? data[position + 1] : 0;
  std::int8_t kind = UNKNOWN;
  if (end == position || first == '#') {
    kind = IGNORE;
  } else if (first == 'v' && second == 't') {
    kind = TEXTURE;  // only counted
  } else if (first == 'v' && second == ' ') {
    kind = VERTEX;
    if (!numbers_line(out, position + 2, end, true)) {
      return false;
    }
  } else if (first == 'v' && second == 'n' && end > position + 2 && is_blank(data[position + 2])) {
    kind = NORMAL;
    if (!numbers_line(out, position + 3, end, false)) {
      return false;
    }
  } else if (first == 'f' && second == ' ') {
    kind = FACE;
    if (!face_line(out, position + 2, end)) {
      return false;
    }
  }
  if (kind == UNKNOWN) {
    const auto row = static_cast<std::int64_t>(out.kinds.size());
    out.unknown.insert(out.unknown.end(), {row, position, end});
  }
  out.kinds.push_back(kind);
  return true;
}

// Whether Python's str.splitlines breaks a line at data[at] where the scan would not: \v \f
// \x1c-\x1e, NEL (0x85), a \r not followed by \n.
bool other_break(const std::uint8_t* data, std::int64_t at, std::int64_t size) {
  const std::uint8_t byte = data[at];
  return byte == 11 || byte == 12 || (byte >= 28 && byte <= 30) || byte == 133 ||
         (byte == '\r' && at + 1 < size && data[at + 1] != '\n');
}

// Every line of the chunk; false to decline it.
bool scan_lines(ObjLines& out, std::int64_t size) {
  const std::uint8_t* data = out.data;
  const std::int64_t reserve = size / 24 + 1;
  out.kinds.reserve(static_cast<std::size_t>(reserve));
  for (std::int64_t position = 0; position < size;) {
    std::int64_t end = position;
    for (; end < size && data[end] != '\n'; ++end) {
      if (other_break(data, end, size)) {
        return false;
      }
    }
    const std::int64_t next = end + 1;
    if (end > position && data[end - 1] == '\r') {
      --end;
    }
    if (!obj_line(out, position, end)) {
      return false;
    }
    position = next;
  }
  return true;
}

// What scan_obj gives for a chunk it reads (see its binding's doc).
using ObjChunk = std::tuple<Array<std::int8_t>, Array<double>, std::optional<Array<double>>,
                            Array<double>, Array<std::int64_t>, std::optional<Array<std::int64_t>>,
                            Array<std::int64_t>, Array<std::int64_t>>;

std::optional<ObjChunk> scan_obj(In<std::uint8_t, nb::ndim<1>> chunk) {
  ObjLines out;
  out.data = chunk.data();
  const auto size = static_cast<std::int64_t>(chunk.shape(0));
  bool read = false;
  {
    nb::gil_scoped_release release;
    read = scan_lines(out, size);
  }
  if (!read) {
    return std::nullopt;
  }
  std::optional<Array<double>> colors;
  if (out.all_colors && !out.vertices.empty()) {
    colors = array_of(std::move(out.colors), 3);
  }
  std::optional<Array<std::int64_t>> normal_ids;
  if (out.all_normals && !out.vertex_ids.empty()) {
    normal_ids = array_of(std::move(out.normal_ids));
  }
  return ObjChunk(array_of(std::move(out.kinds)), array_of(std::move(out.vertices), 3), colors,
                  array_of(std::move(out.normals), 3), array_of(std::move(out.vertex_ids)),
                  normal_ids, array_of(std::move(out.counts)), array_of(std::move(out.unknown), 3));
}

// One item of `Size` bytes at `at`, in the file's byte order, as int64.
template <typename Unsigned, typename Signed>
std::int64_t item(const std::uint8_t* at, bool swap, bool is_signed) {
  Unsigned value;
  std::memcpy(&value, at, sizeof value);
  if (swap) {
    Unsigned swapped = 0;
    for (std::size_t k = 0; k < sizeof value; ++k) {
      swapped = static_cast<Unsigned>((swapped << 8) | ((value >> (8 * k)) & 0xFF));
    }
    value = swapped;
  }
  return is_signed ? static_cast<std::int64_t>(static_cast<Signed>(value))
                   : static_cast<std::int64_t>(value);
}

template <typename Unsigned, typename Signed>
void items_of(const std::uint8_t* data, std::int64_t offset, std::int64_t stride, bool swap,
              bool is_signed, std::int64_t* out, std::int64_t rows, std::int64_t columns) {
  parallel_for(rows, 1 << 14, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      const std::uint8_t* record = data + offset + i * stride;
      for (std::int64_t j = 0; j < columns; ++j) {
        out[i * columns + j] =
            item<Unsigned, Signed>(record + j * std::int64_t{sizeof(Unsigned)}, swap, is_signed);
      }
    }
  });
}

bool little_endian_host() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void binary_items(In<std::uint8_t, nb::ndim<1>> data, std::int64_t offset, std::int64_t stride,
                  std::int64_t size, bool is_signed, bool little,
                  Out<std::int64_t, nb::ndim<2>> items) {
  const auto rows = static_cast<std::int64_t>(items.shape(0));
  const auto columns = static_cast<std::int64_t>(items.shape(1));
  const auto length = static_cast<std::int64_t>(data.shape(0));
  if (size != 1 && size != 2 && size != 4) {
    throw nb::value_error("A list item must be 1, 2 or 4 bytes.");
  }
  if (columns == 0 || rows == 0) {
    return;
  }
  if (offset < 0 || stride < 1 || stride < size * columns) {
    throw nb::value_error("The records' offset or stride does not hold their lists.");
  }
  // The last record's items end at offset + (rows - 1) * stride + columns * size.
  const std::int64_t room = length - offset - columns * size;
  if (room < 0 || (rows - 1) > room / stride) {
    throw nb::index_error("The records' lists reach past the end of the data.");
  }
  const bool swap = little != little_endian_host();
  const std::uint8_t* bytes = data.data();
  std::int64_t* out = items.data();
  nb::gil_scoped_release release;
  if (size == 1) {
    items_of<std::uint8_t, std::int8_t>(bytes, offset, stride, swap, is_signed, out, rows, columns);
  } else if (size == 2) {
    items_of<std::uint16_t, std::int16_t>(bytes, offset, stride, swap, is_signed, out, rows,
                                          columns);
  } else {
    items_of<std::uint32_t, std::int32_t>(bytes, offset, stride, swap, is_signed, out, rows,
                                          columns);
  }
}

// The decimal of the whole of `text` as the OBJ scan reads it, or None (for tests).
std::optional<double> read_decimal(const std::string& text) {
  const auto* data = reinterpret_cast<const std::uint8_t*>(text.data());
  const auto end = static_cast<std::int64_t>(text.size());
  std::int64_t stop = 0;
  double value = 0.0;
  if (!decimal(data, 0, end, stop, value) || stop != end) {
    return std::nullopt;
  }
  return value;
}

}  // namespace

void bind_text(nb::module_& m) {
  m.def("scan_obj", &scan_obj, nb::arg("chunk").noconvert(),
        "The lines of an OBJ chunk (whole lines): (kinds, vertices, colours or None, normals, "
        "corner vertex indices, corner normal indices or None, corners per face, (row, start, "
        "end) of each line left to the caller), or None where the scan cannot certify it.");
  m.def("binary_items", &binary_items, nb::arg("data").noconvert(), nb::arg("offset"),
        nb::arg("stride"), nb::arg("size"), nb::arg("signed"), nb::arg("little"),
        nb::arg("items").noconvert(),
        "The integers of `size` bytes (1, 2 or 4) at data[offset + i * stride + j * size] "
        "into items[i, j]: a binary PLY's lists of one length, read from its records.");
  m.def("read_decimal", &read_decimal, nb::arg("text"),
        "The decimal `text` as the OBJ scan reads it (float()'s bits), or None where the scan "
        "declines it.");
}

}  // namespace mesh_normal
