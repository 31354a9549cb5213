// Text and binary parsing: an OBJ chunk's statements read from its bytes, and a binary PLY's
// integer lists read from its records.
//
// The OBJ scan reads a chunk's bytes as Latin-1 text, as Python's str methods see it: lines end
// where str.splitlines() ends them, words are split where str.split() splits them, numbers are
// float()'s (bit for bit) and indices int()'s, underscores between digits and all.
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>

#include "core.hpp"

namespace mesh_normal {

namespace {

template <typename T>
using Array = nb::ndarray<nb::numpy, T>;

// A NumPy array that owns a vector's memory (no copy); the capsule is made while a unique_ptr
// still holds the vector, so a throw frees it.
template <typename T>
Array<T> array_of(std::vector<T>&& values, std::size_t columns = 0) {
  auto held = std::make_unique<std::vector<T>>(std::move(values));
  nb::capsule owner(held.get(), [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
  std::vector<T>* vector = held.release();
  const std::size_t count = columns ? vector->size() / columns : vector->size();
  if (columns == 0) {
    return Array<T>(vector->data(), {count}, owner);
  }
  return Array<T>(vector->data(), {count, columns}, owner);
}

// Where str.splitlines() ends a line of Latin-1 text (\n, \r, \v, \f, \x1c-\x1e, NEL; \r\n is
// one end), and what else str.split() separates words at within a line (space, tab, \x1f and
// the no-break space).
constexpr std::uint8_t BREAK = 1, SPACE = 2;
constexpr std::array<std::uint8_t, 256> character_classes() {
  std::array<std::uint8_t, 256> classes{};
  for (const int code : {0x0a, 0x0d, 0x0b, 0x0c, 0x1c, 0x1d, 0x1e, 0x85}) {
    classes[static_cast<std::size_t>(code)] = BREAK;
  }
  for (const int code : {0x20, 0x09, 0x1f, 0xa0}) {
    classes[static_cast<std::size_t>(code)] = SPACE;
  }
  return classes;
}
constexpr std::array<std::uint8_t, 256> CLASSES = character_classes();

bool is_break(char c) { return CLASSES[static_cast<std::uint8_t>(c)] == BREAK; }
bool is_space(char c) { return CLASSES[static_cast<std::uint8_t>(c)] == SPACE; }
constexpr bool is_digit(char c) { return c >= '0' && c <= '9'; }

// The next word of `line` from `i` (empty at the line's end); `i` moves past it.
std::string_view next_word(std::string_view line, std::size_t& i) {
  while (i < line.size() && is_space(line[i])) {
    ++i;
  }
  const std::size_t start = i;
  while (i < line.size() && !is_space(line[i])) {
    ++i;
  }
  return line.substr(start, i - start);
}

// `text` without its underscores, where each stands between two digits as float() and int()
// allow; false where one does not.
bool without_underscores(std::string_view text, std::string& plain) {
  char previous = 0;
  for (const char c : text) {
    if (c == '_' ? !is_digit(previous) : previous == '_' && !is_digit(c)) {
      return false;
    }
    if (c != '_') {
      plain.push_back(c);
    }
    previous = c;
  }
  return previous != '_';
}

// Whether `text` is `lower` in any case.
bool same_letters(std::string_view text, std::string_view lower) {
  if (text.size() != lower.size()) {
    return false;
  }
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k] >= 'A' && text[k] <= 'Z' ? static_cast<char>(text[k] + 32) : text[k];
    if (c != lower[k]) {
      return false;
    }
  }
  return true;
}

// An unsigned decimal, `digits[.digits][(e|E)[+-]digits]` with a digit in its mantissa, as the
// nearest double (std::from_chars and float() both round correctly, so the bits agree); false
// when `text` is not one.
bool unsigned_decimal(std::string_view text, double& value) {
  const std::size_t end = text.size();
  std::size_t i = 0;
  // Where the first significant digit stands against the point, to tell an overflow from an
  // underflow when from_chars finds the value out of range.
  std::int64_t magnitude = 0;
  bool seen = false, significant = false;
  for (; i < end && is_digit(text[i]); ++i) {
    seen = true;
    significant = significant || text[i] != '0';
    magnitude += significant ? 1 : 0;
  }
  if (i < end && text[i] == '.') {
    for (++i; i < end && is_digit(text[i]); ++i) {
      seen = true;
      significant = significant || text[i] != '0';
      magnitude -= significant ? 0 : 1;
    }
  }
  if (!seen) {
    return false;
  }
  if (i < end && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    const bool minus = i < end && text[i] == '-';
    if (i < end && (text[i] == '+' || text[i] == '-')) {
      ++i;
    }
    if (i >= end || !is_digit(text[i])) {
      return false;
    }
    std::int64_t power = 0;
    for (; i < end && is_digit(text[i]); ++i) {
      power = power < 100000 ? power * 10 + (text[i] - '0') : power;
    }
    magnitude += minus ? -power : power;
  }
  if (i != end) {
    return false;
  }
  const char* last = text.data() + end;
  double read = 0.0;
  const auto [ptr, error] = std::from_chars(text.data(), last, read, std::chars_format::general);
  if (ptr != last || (error != std::errc() && error != std::errc::result_out_of_range)) {
    return false;
  }
  if (error == std::errc::result_out_of_range) {
    // float() gives infinity past the largest double and zero below half the smallest.
    read = magnitude > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  }
  value = read;
  return true;
}

// float() of a word without underscores: a sign, then inf, infinity or nan in any case, or an
// unsigned decimal; false where float() raises.
bool plain_float(std::string_view text, double& value) {
  const bool negative = !text.empty() && text[0] == '-';
  if (!text.empty() && (text[0] == '+' || text[0] == '-')) {
    text.remove_prefix(1);
  }
  const double sign = negative ? -1.0 : 1.0;
  if (!unsigned_decimal(text, value)) {
    if (same_letters(text, "inf") || same_letters(text, "infinity")) {
      value = std::copysign(std::numeric_limits<double>::infinity(), sign);
      return true;
    }
    if (same_letters(text, "nan")) {
      value = std::copysign(std::numeric_limits<double>::quiet_NaN(), sign);  // "-nan": sign bit
      return true;
    }
    return false;
  }
  value = std::copysign(value, sign);
  return true;
}

// float() of a word, single underscores between digits allowed.
bool python_float(std::string_view text, double& value) {
  if (plain_float(text, value)) {
    return true;
  }
  std::string plain;
  return text.find('_') != std::string_view::npos && without_underscores(text, plain) &&
         plain_float(plain, value);
}

// What int() makes of a word: no integer, an integer, or one past int64.
enum class Integer { NONE, READ, TOO_LARGE };

// int() of a word without underscores: a sign, then digits.
Integer plain_int(std::string_view text, std::int64_t& value) {
  const bool negative = !text.empty() && text[0] == '-';
  if (!text.empty() && (text[0] == '+' || text[0] == '-')) {
    text.remove_prefix(1);
  }
  if (text.empty()) {
    return Integer::NONE;
  }
  // The magnitude's limit: 2**63 for a negative value, 2**63 - 1 otherwise. Eighteen digits
  // always fit; only a longer number is checked digit by digit.
  const std::uint64_t limit = std::uint64_t{1} << 63U;
  const std::uint64_t top = negative ? limit : limit - 1;
  std::uint64_t read = 0;
  bool large = false;
  for (std::size_t k = 0; k < text.size(); ++k) {
    if (!is_digit(text[k])) {
      return Integer::NONE;
    }
    const auto digit = static_cast<std::uint64_t>(text[k] - '0');
    large = large || (k >= 18 && read > (top - digit) / 10);
    read = large ? read : read * 10 + digit;
  }
  if (large) {
    return Integer::TOO_LARGE;
  }
  value = negative ? static_cast<std::int64_t>(0 - read) : static_cast<std::int64_t>(read);
  return Integer::READ;
}

// int() of a word, single underscores between digits allowed.
Integer python_int(std::string_view text, std::int64_t& value) {
  const Integer read = plain_int(text, value);
  if (read != Integer::NONE || text.find('_') == std::string_view::npos) {
    return read;
  }
  std::string plain;
  return without_underscores(text, plain) ? plain_int(plain, value) : Integer::NONE;
}

// The statements the scan tells apart.
enum Kind { IGNORE, VERTEX, NORMAL, TEXTURE, FACE, OBJECT, GROUP, OTHER };

// What stops the scan of a file: (code, line, text, number) for the caller's sentence.
enum Failure : std::int64_t { TOO_FEW = 1, NOT_A_NUMBER = 2, BAD_CORNER = 3, TOO_LARGE = 4 };

// A line's kind: `v `, `vn`, `vt`, `f `, `o ` or `g ` at its start, or else its first word
// (`key`, which is counted when the kind is OTHER); comments and blank lines are IGNORE.
Kind kind_of(std::string_view line, std::string_view& key) {
  if (line.size() >= 2) {
    const char first = line[0], second = line[1];
    if (first == 'v') {
      if (second == ' ') {
        return VERTEX;
      }
      if (second == 'n') {
        return NORMAL;
      }
      if (second == 't') {
        return TEXTURE;
      }
    }
    if (second == ' ' && (first == 'f' || first == 'o' || first == 'g')) {
      return first == 'f' ? FACE : first == 'o' ? OBJECT : GROUP;
    }
  }
  std::size_t i = 0;
  key = next_word(line, i);
  if (key.empty() || key[0] == '#') {
    return IGNORE;
  }
  if (key.size() <= 2) {
    for (const auto& [word, kind] : {std::pair<std::string_view, Kind>{"v", VERTEX},
                                     {"vn", NORMAL},
                                     {"vt", TEXTURE},
                                     {"f", FACE},
                                     {"o", OBJECT},
                                     {"g", GROUP}}) {
      if (key == word) {
        return kind;
      }
    }
  }
  return OTHER;
}

// What the scan of one chunk finds (see scan_obj's binding), line numbers counted from its
// first line.
struct Scan {
  std::vector<double> vertices, colors, normals;
  std::vector<std::int64_t> vertex_lines, vertex_ids, normal_ids, counts, face_lines;
  std::vector<std::int64_t> vertices_before, normals_before;
  std::int64_t lines = 0, textures = 0;
  bool all_colors = true, all_normals = true;
  // The `o` (true) and `g` statements: the faces before each, and its name.
  std::vector<std::tuple<bool, std::int64_t, std::string>> groups;
  // Each other statement's keyword and count, in the order first met.
  std::vector<std::pair<std::string, std::int64_t>> skipped;
  std::unordered_map<std::string, std::size_t> skipped_at;
  std::optional<std::tuple<std::int64_t, std::int64_t, std::string, std::int64_t>> failure;
  std::string joined;  // a continued line's pieces
};

bool fail(Scan& scan, Failure code, std::int64_t line, std::string_view text,
          std::int64_t number = 0) {
  scan.failure.emplace(code, line, std::string(text), number);
  return false;
}

// The three numbers after a `v` or `vn` keyword: the first three words after it, as float()
// reads them (what follows is the colours' business).
bool coordinates(Scan& scan, std::string_view line, std::int64_t number, bool vertex,
                 std::vector<double>& target) {
  std::size_t i = 0;
  next_word(line, i);  // the keyword
  std::string_view words[3];
  std::int64_t count = 0;
  for (; count < 3; ++count) {
    words[count] = next_word(line, i);
    if (words[count].empty()) {
      return fail(scan, TOO_FEW, number, vertex ? "v" : "vn", count);
    }
  }
  for (const std::string_view word : words) {
    double value = 0.0;
    if (!python_float(word, value)) {
      return fail(scan, NOT_A_NUMBER, number, word);
    }
    target.push_back(value);
  }
  return true;
}

// The colours of a `v x y z r g b` line: exactly seven words before any `#`, the last three
// numbers. A file whose `v` lines do not all have them has none.
void colors(Scan& scan, std::string_view line) {
  line = line.substr(0, line.find('#'));
  std::size_t i = 0;
  std::int64_t count = 0;
  double rgb[3] = {0, 0, 0};
  for (std::string_view word = next_word(line, i); !word.empty(); word = next_word(line, i)) {
    if (count >= 7 || (count >= 4 && !python_float(word, rgb[count - 4]))) {
      scan.all_colors = false;
      return;
    }
    ++count;
  }
  scan.all_colors = count == 7;
  if (scan.all_colors) {
    scan.colors.insert(scan.colors.end(), rgb, rgb + 3);
  }
}

// One face corner: `v`, `v/vt` or `v/vt/vn`, where the texture and normal may be empty; each
// an integer, though a texture index of any size (it is not used).
bool corner(Scan& scan, std::string_view word, std::int64_t number) {
  std::string_view fields[3];
  std::size_t count = 0, start = 0;
  for (;;) {
    const std::size_t slash = word.find('/', start);
    if (count == 3) {
      return fail(scan, BAD_CORNER, number, word);
    }
    fields[count++] = word.substr(start, slash == std::string_view::npos ? slash : slash - start);
    if (slash == std::string_view::npos) {
      break;
    }
    start = slash + 1;
  }
  if (fields[0].empty()) {
    return fail(scan, BAD_CORNER, number, word);
  }
  std::int64_t values[3] = {0, 0, 0};
  std::int64_t large = -1;  // the first field past int64
  for (std::size_t k = 0; k < count; ++k) {
    if (fields[k].empty()) {
      continue;
    }
    const Integer read = python_int(fields[k], values[k]);
    if (read == Integer::NONE) {
      return fail(scan, BAD_CORNER, number, word);
    }
    if (read == Integer::TOO_LARGE && k != 1 && large < 0) {  // texture indices go unused
      large = static_cast<std::int64_t>(k);
    }
  }
  if (large >= 0) {
    return fail(scan, TOO_LARGE, number, fields[large], large);
  }
  const bool has_normal = count == 3 && !fields[2].empty();
  scan.all_normals = scan.all_normals && has_normal;
  scan.vertex_ids.push_back(values[0]);
  scan.normal_ids.push_back(values[2]);
  return true;
}

// The corners of an `f` line: its words after the keyword, up to any `#`.
bool face(Scan& scan, std::string_view line, std::int64_t number) {
  line = line.substr(0, line.find('#'));
  std::size_t i = 0;
  next_word(line, i);  // the keyword
  std::int64_t count = 0;
  for (std::string_view word = next_word(line, i); !word.empty(); word = next_word(line, i)) {
    if (!corner(scan, word, number)) {
      return false;
    }
    ++count;
  }
  scan.counts.push_back(count);
  scan.face_lines.push_back(number);
  scan.vertices_before.push_back(static_cast<std::int64_t>(scan.vertex_lines.size()));
  scan.normals_before.push_back(static_cast<std::int64_t>(scan.normals.size() / 3));
  return true;
}

// An `o` or `g` statement: the words after the keyword, up to any `#`, as one name.
void group(Scan& scan, std::string_view line, bool object) {
  line = line.substr(0, line.find('#'));
  std::size_t i = 0;
  next_word(line, i);  // the keyword
  std::string name;
  for (std::string_view word = next_word(line, i); !word.empty(); word = next_word(line, i)) {
    if (!name.empty()) {
      name.push_back(' ');
    }
    name.append(word);
  }
  scan.groups.emplace_back(object, static_cast<std::int64_t>(scan.counts.size()), std::move(name));
}

// One statement (a line, or a continued line's pieces joined), from line `number`.
bool statement(Scan& scan, std::string_view line, std::int64_t number) {
  std::string_view key;
  switch (kind_of(line, key)) {
    case VERTEX:
      if (!coordinates(scan, line, number, true, scan.vertices)) {
        return false;
      }
      scan.vertex_lines.push_back(number);
      if (scan.all_colors) {
        colors(scan, line);
      }
      return true;
    case NORMAL:
      return coordinates(scan, line, number, false, scan.normals);
    case TEXTURE:
      ++scan.textures;
      return true;
    case FACE:
      return face(scan, line, number);
    case OBJECT:
    case GROUP:
      group(scan, line, line[0] == 'o' || key == "o");
      return true;
    case OTHER: {
      const auto [at, added] = scan.skipped_at.try_emplace(std::string(key), scan.skipped.size());
      if (added) {
        scan.skipped.emplace_back(key, 0);
      }
      ++scan.skipped[at->second].second;
      return true;
    }
    case IGNORE:
      return true;
  }
  return true;
}

// Every line of the chunk, until one fails. A line whose last visible character is a backslash
// continues on the next, joined by a space; a comment line does not (`# saved in C:\models\`
// would swallow the statement after it), unless it is itself a continuation.
void scan_lines(Scan& scan, std::string_view text) {
  std::int64_t number = 0, first = 0;  // the line's number, and a continued line's first
  bool pending = false;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = start;
    while (end < text.size() && !is_break(text[end])) {
      ++end;
    }
    const bool crlf = end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n';
    const std::string_view line = text.substr(start, end - start);
    start = end + (crlf ? 2 : 1);
    ++number;
    std::size_t kept = line.size();
    while (kept > 0 && is_space(line[kept - 1])) {
      --kept;
    }
    if (kept > 0 && line[kept - 1] == '\\') {
      std::size_t i = 0;
      if (pending || next_word(line, i)[0] != '#') {
        if (pending) {
          scan.joined.push_back(' ');
        } else {
          scan.joined.clear();
          first = number;
          pending = true;
        }
        scan.joined.append(line.substr(0, kept - 1));
        continue;
      }
    }
    bool read = true;
    if (pending) {
      scan.joined.push_back(' ');
      scan.joined.append(line);
      pending = false;
      read = statement(scan, scan.joined, first);
    } else {
      read = statement(scan, line, number);
    }
    if (!read) {
      return;
    }
  }
  if (pending) {
    statement(scan, scan.joined, first);
  }
  scan.lines = number;
}

// What scan_obj gives for a chunk (see its binding's doc).
struct ObjChunk {
  Array<double> vertices, normals;
  std::optional<Array<double>> colors;
  Array<std::int64_t> vertex_lines, vertex_ids, counts, face_lines, vertices_before,
      normals_before;
  std::optional<Array<std::int64_t>> normal_ids;
  std::int64_t lines = 0, textures = 0;
  std::vector<std::tuple<bool, std::int64_t, nb::bytes>> groups;
  std::vector<std::tuple<nb::bytes, std::int64_t>> skipped;
  std::optional<std::tuple<std::int64_t, std::int64_t, nb::bytes, std::int64_t>> failure;
};

nb::bytes bytes_of(const std::string& text) { return nb::bytes(text.data(), text.size()); }

ObjChunk scan_obj(In<std::uint8_t, nb::ndim<1>> chunk) {
  Scan scan;
  {
    nb::gil_scoped_release release;
    scan_lines(scan, std::string_view(reinterpret_cast<const char*>(chunk.data()), chunk.shape(0)));
  }
  ObjChunk out;
  const bool any_vertex = !scan.vertex_lines.empty(), any_corner = !scan.vertex_ids.empty();
  out.vertices = array_of(std::move(scan.vertices), 3);
  out.normals = array_of(std::move(scan.normals), 3);
  if (scan.all_colors && any_vertex) {
    out.colors = array_of(std::move(scan.colors), 3);
  }
  out.vertex_lines = array_of(std::move(scan.vertex_lines));
  out.vertex_ids = array_of(std::move(scan.vertex_ids));
  if (scan.all_normals && any_corner) {
    out.normal_ids = array_of(std::move(scan.normal_ids));
  }
  out.counts = array_of(std::move(scan.counts));
  out.face_lines = array_of(std::move(scan.face_lines));
  out.vertices_before = array_of(std::move(scan.vertices_before));
  out.normals_before = array_of(std::move(scan.normals_before));
  out.lines = scan.lines;
  out.textures = scan.textures;
  for (const auto& [object, faces, name] : scan.groups) {
    out.groups.emplace_back(object, faces, bytes_of(name));
  }
  for (const auto& [key, count] : scan.skipped) {
    out.skipped.emplace_back(bytes_of(key), count);
  }
  if (scan.failure) {
    const auto& [code, line, text, number] = *scan.failure;
    out.failure.emplace(code, line, bytes_of(text), number);
  }
  return out;
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

// float() of `text` as the OBJ scan reads a word, or None where float() raises (for tests).
std::optional<double> read_decimal(const std::string& text) {
  double value = 0.0;
  if (!python_float(text, value)) {
    return std::nullopt;
  }
  return value;
}

}  // namespace

void bind_text(nb::module_& m) {
  // The arrays are the ObjChunk's own (their capsules hold them), so they are handed out as
  // they are: each Python array keeps its buffer alive.
  constexpr auto as_is = nb::rv_policy::reference;
  nb::class_<ObjChunk>(
      m, "ObjChunk",
      "What scan_obj reads in a chunk of whole lines, line numbers counted from its first.")
      .def_ro("vertices", &ObjChunk::vertices, as_is, "(n, 3) the `v` coordinates")
      .def_ro("colors", &ObjChunk::colors, as_is,
              "(n, 3) their colours, or None unless every `v` has `r g b`")
      .def_ro("vertex_lines", &ObjChunk::vertex_lines, as_is, "(n,) the line of each `v`")
      .def_ro("normals", &ObjChunk::normals, as_is, "(k, 3) the `vn` vectors")
      .def_ro("vertex_ids", &ObjChunk::vertex_ids, as_is,
              "(c,) each corner's vertex index as written")
      .def_ro("normal_ids", &ObjChunk::normal_ids, as_is,
              "(c,) its normal index, or None unless every corner has one")
      .def_ro("counts", &ObjChunk::counts, as_is, "(p,) the corners of each `f`")
      .def_ro("face_lines", &ObjChunk::face_lines, as_is, "(p,) the line of each `f`")
      .def_ro("vertices_before", &ObjChunk::vertices_before, as_is,
              "(p,) the `v` statements before each `f`")
      .def_ro("normals_before", &ObjChunk::normals_before, as_is,
              "(p,) the `vn` statements before each `f`")
      .def_ro("lines", &ObjChunk::lines, "how many lines the chunk has")
      .def_ro("textures", &ObjChunk::textures, "how many `vt` statements")
      .def_ro("groups", &ObjChunk::groups,
              "(is `o`, faces before it, name) of each `o` and `g` statement")
      .def_ro("skipped", &ObjChunk::skipped,
              "(keyword, count) of the other statements, in the order first met")
      .def_ro("failure", &ObjChunk::failure,
              "None, or what stopped the scan: (code, line, text, number), codes 1 too few "
              "numbers (number: how many), 2 not a number, 3 not a corner, 4 a vertex or normal "
              "index past int64 (number: 0 vertex, 2 normal)");
  m.def("scan_obj", &scan_obj, nb::arg("chunk").noconvert(),
        "The statements of a chunk of an OBJ file, whole lines, read as Latin-1 text as Python "
        "reads it (see ObjChunk).");
  m.def("binary_items", &binary_items, nb::arg("data").noconvert(), nb::arg("offset"),
        nb::arg("stride"), nb::arg("size"), nb::arg("signed"), nb::arg("little"),
        nb::arg("items").noconvert(),
        "The integers of `size` bytes (1, 2 or 4) at data[offset + i * stride + j * size] "
        "into items[i, j]: a binary PLY's lists of one length, read from its records.");
  m.def("read_decimal", &read_decimal, nb::arg("text"),
        "float(text) as the OBJ scan reads a word, to the bit, or None where float() raises.");
}

}  // namespace mesh_normal
