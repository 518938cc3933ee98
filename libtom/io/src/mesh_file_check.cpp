// Structural checks of OFF, PLY, OBJ and STL files before OpenMesh reads them, and the canonical
// text it reads in place of a text file.
//
// OpenMesh's readers trust their input: a PLY header with an unknown type or a broken line makes
// its format detection loop forever or crash, a face announcing a billion corners is read corner
// by corner past the end of the file, an OBJ face naming a vertex the file does not have is
// written out of bounds. One pass here finds those (counts against what the file can hold,
// indices against what it defines, every announced number present) and names the line.
// Checking alone is not enough: wherever OpenMesh's tokenizing differs from this one (a '#'
// inside a line, a comment before the counts, a value past a face's corners) the two would read
// different files. So a text file is rewritten as what was checked, one token per value with
// single spaces, comments and unused lines dropped, OBJ indices made absolute, and OpenMesh
// reads that. A binary PLY body, whose layout was walked byte by byte, follows a canonical header
// as it is; binary OFF (whose header line must be canonical already) and STL are read from the
// file.
// Values themselves (non-finite coordinates, degenerate faces) are cleaned later.

#include "mesh_file_check.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <charconv>
#include <cstring>
#include <strings.h>
#include <map>
#include <string_view>
#include <vector>

#include "import_backends.h"
#include "tom/errors.h"

namespace tom::detail {

namespace {

// Whitespace-separated tokens of a text, line by line; '#' starts a comment to the end of its
// line.
class Tokens {
  public:
    explicit Tokens(std::string_view text) : text_(text) {}

    // The next token on any line.
    bool next(std::string_view& token) {
        while (!on_line(token)) {
            if (at_ >= text_.size()) return false;
            end_line();
        }
        return true;
    }
    // The rest of the current line, as tokens; moves to the next line.
    void rest_of_line(std::vector<std::string_view>& out) {
        out.clear();
        last_line_ = line_;
        for (std::string_view t; on_line(t);) out.push_back(t);
        end_line();
    }
    // The next line that is not empty or a comment, as tokens; false at the end.
    bool line(std::vector<std::string_view>& out) {
        while (at_ < text_.size()) {
            rest_of_line(out);
            if (!out.empty()) return true;
        }
        return false;
    }
    size_t line_number() const { return line_; }     // where reading is now
    size_t last_line() const { return last_line_; }  // of the last line() or rest_of_line()
    size_t offset() const { return at_; }

  private:
    static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }
    // The next token before the end of the current line (a comment ends it); false at its end.
    bool on_line(std::string_view& token) {
        while (at_ < text_.size() && text_[at_] != '\n' && is_space(text_[at_])) ++at_;
        if (at_ >= text_.size() || text_[at_] == '\n' || text_[at_] == '#') return false;
        const size_t begin = at_;
        while (at_ < text_.size() && !is_space(text_[at_])) ++at_;
        token = text_.substr(begin, at_ - begin);
        return true;
    }
    void end_line() {
        while (at_ < text_.size() && text_[at_] != '\n') ++at_;
        if (at_ < text_.size()) ++at_, ++line_;
    }
    std::string_view text_;
    size_t at_ = 0;
    size_t line_ = 1, last_line_ = 1;
};

// As strtoll reads a whole token: optional sign, decimal digits, in range.
bool parse_integer(std::string_view s, long long& value) {
    if (s.empty() || s.size() > 20) return false;
    const char* first = s.data() + (s[0] == '+' && s.size() > 1 && s[1] != '-' ? 1 : 0);
    const auto [end, error] = std::from_chars(first, s.data() + s.size(), value);
    return error == std::errc() && end == s.data() + s.size();
}

// A number as an input stream reads it into a float: decimal digits with an optional sign,
// point and exponent, within float range (no nan, inf or hexadecimal: the stream stops there,
// and OpenMesh's readers then read every later value from a failed stream). With `prefix`, only
// the start of `s` must be such a number: the stream stops where it ends and leaves the rest, so
// "3.1+e2" reads 3.1 but "%0" reads nothing (OpenMesh's OBJ reader then adds no vertex).
bool parse_number(std::string_view s, bool prefix = false, size_t* used = nullptr) {
    size_t i = 0;
    auto digits = [&] {
        const size_t start = i;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
        return i > start;
    };
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    const size_t integer_start = i;
    bool mantissa = digits();
    const size_t integer_end = i;
    size_t fraction_start = i, fraction_end = i;
    if (i < s.size() && s[i] == '.') {
        ++i;
        fraction_start = i;
        mantissa |= digits();
        fraction_end = i;
    }
    if (!mantissa) return false;
    long exponent = 0;
    bool has_exponent = false;
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        const size_t marker = i++;
        const bool negative = i < s.size() && s[i] == '-';
        if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
        const size_t exponent_start = i;
        if (digits()) {
            for (size_t k = exponent_start; k < i && exponent < 100000; ++k) exponent = exponent * 10 + (s[k] - '0');
            if (negative) exponent = -exponent;
            has_exponent = true;
        } else if (prefix) {
            i = marker;  // the stream reads no exponent there
        } else {
            return false;
        }
    }
    if (prefix) s = s.substr(0, i);
    if (i != s.size() || s.size() > 64) return false;
    if (used) *used = i;
    // the decimal magnitude of the first non-zero digit: within 1e-30..1e30 the value is a
    // finite, normal float, and strtof (what the range check below asks) cannot fail
    long magnitude = 0;
    bool nonzero = false;
    for (size_t k = integer_start; k < integer_end && !nonzero; ++k)
        if (s[k] != '0') nonzero = true, magnitude = long(integer_end - k) - 1;
    for (size_t k = fraction_start; k < fraction_end && !nonzero; ++k)
        if (s[k] != '0') nonzero = true, magnitude = -long(k - fraction_start) - 1;
    if (!nonzero && !has_exponent) return true;  // zero
    if (nonzero && magnitude + exponent >= -30 && magnitude + exponent <= 30) return true;
    char buffer[72];
    std::memcpy(buffer, s.data(), s.size());
    buffer[s.size()] = 0;
    errno = 0;
    const float value = std::strtof(buffer, nullptr);
    return errno != ERANGE && std::isfinite(value);
}

[[noreturn]] void fail(const std::string& path, size_t line, const std::string& problem) {
    throw MeshError(path + ":" + std::to_string(line) + ": " + problem);
}

std::string quoted(std::string_view s) { return "'" + std::string(s.substr(0, 40)) + (s.size() > 40 ? "...'" : "'"); }

// The canonical text: tokens separated by one space, lines by '\n'.
struct Canonical {
    std::string text;
    void line(std::initializer_list<std::string_view> tokens) {
        bool first = true;
        for (std::string_view t : tokens) {
            if (!first) text += ' ';
            text.append(t.data(), t.size());
            first = false;
        }
        text += '\n';
    }
    void line(const std::vector<std::string_view>& tokens, size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) {
            if (k > begin) text += ' ';
            text.append(tokens[k].data(), tokens[k].size());
        }
        text += '\n';
    }
};

// ---- OFF --------------------------------------------------------------------------------------

// [ST][C][N]OFF [BINARY]: the variants OpenMesh reads (it refuses 4OFF and nOFF)
struct OffHeader {
    bool texcoords = false, colors = false, normals = false, binary = false;
};

bool parse_off_keyword(std::string_view k, OffHeader& h, bool& other_dimension) {
    size_t i = 0;
    auto take = [&](std::string_view prefix) {
        if (k.substr(i, prefix.size()) != prefix) return false;
        i += prefix.size();
        return true;
    };
    h.texcoords = take("ST");
    h.colors = take("C");
    h.normals = take("N");
    other_dimension = take("4");
    other_dimension |= take("n");
    return take("OFF") && i == k.size();
}

// Checks an OFF file and writes the canonical text into `out` (nothing for BINARY, read from the
// file).
void check_off(const std::string& path, std::string_view text, Canonical& out) {
    Tokens in(text);
    std::vector<std::string_view> words;
    if (!in.line(words)) fail(path, 1, "no OFF header");
    OffHeader h;
    bool other_dimension = false;
    if (!parse_off_keyword(words[0], h, other_dimension)) fail(path, in.last_line(), "expected an OFF header keyword, found " + quoted(words[0]));
    if (other_dimension) fail(path, in.last_line(), quoted(words[0]) + ": only three-dimensional vertices are supported");
    h.binary = words.size() > 1 && words[1] == "BINARY";
    // OpenMesh reads the counts from the line after the keyword's and ignores the rest of the
    // keyword's line: counts there would be checked here and never read there
    if (words.size() > (h.binary ? 2u : 1u))
        fail(path, in.last_line(), quoted(words[h.binary ? 2 : 1]) + " after " + quoted(words[0]) + ": the vertex, face and edge counts must start the next line");
    if (h.binary) {
        // 32-bit little-endian counts and values after the header line, read from the file (an
        // OpenMesh stream cannot be told it is binary). OpenMesh takes the file as binary only
        // when " BINARY" follows the keyword with one space on the first line; otherwise it
        // would read the binary body as text
        const std::string_view first = text.substr(0, text.find('\n'));
        if (in.last_line() != 1 || first != std::string(words[0]) + " BINARY")
            fail(path, in.last_line(), "a binary OFF file must start with the line '" + std::string(words[0]) + " BINARY', found " + quoted(first));
        size_t at = in.offset();
        auto word = [&](uint32_t& v) {
            if (at + 4 > text.size()) return false;
            std::memcpy(&v, text.data() + at, 4);
            at += 4;
            return true;
        };
        uint32_t nv = 0, nf = 0, ne = 0;
        if (!word(nv) || !word(nf) || !word(ne)) fail(path, in.line_number(), "the file ends before the binary counts");
        const uint64_t per_vertex = 12 + (h.normals ? 12 : 0) + (h.colors ? 12 : 0) + (h.texcoords ? 8 : 0);
        const uint64_t left = text.size() - at;
        if (uint64_t(nv) * per_vertex + uint64_t(nf) * 16 > left)
            fail(path, in.line_number(), std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces cannot fit in the " + std::to_string(left) + " bytes that follow");
        if (h.colors) return;  // colour sizes vary: the counts are all that can be checked
        at += size_t(uint64_t(nv) * per_vertex);
        for (uint32_t f = 0; f < nf; ++f) {
            uint32_t n = 0, index = 0;
            if (!word(n)) fail(path, in.line_number(), "the data ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
            if (n < 1 || n > nv || uint64_t(n) * 4 > text.size() - at) fail(path, in.line_number(), "binary face " + std::to_string(f) + " announces " + std::to_string(n) + " corners");
            for (uint32_t k = 0; k < n; ++k)
                if (word(index) && index >= nv) fail(path, in.line_number(), "binary face " + std::to_string(f) + " refers to vertex " + std::to_string(index) + ", the file has " + std::to_string(nv));
        }
        return;
    }
    std::vector<std::string_view> counts;
    if (!in.line(counts)) fail(path, in.line_number(), "the file ends before the vertex, face and edge counts");
    const size_t count_line = in.last_line();
    long long nv = 0, nf = 0;
    if (counts.size() < 2 || !parse_integer(counts[0], nv) || !parse_integer(counts[1], nf) || nv < 0 || nf < 0)
        fail(path, count_line, "expected the vertex, face and edge counts");
    // every vertex and face takes at least a few bytes of text
    if (uint64_t(nv) > text.size() / 4 || uint64_t(nf) > text.size() / 4)
        fail(path, count_line, std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces cannot fit in a file of " + std::to_string(text.size()) + " bytes");
    const std::string nv_text = std::to_string(nv), nf_text = std::to_string(nf);
    out.line({words[0]});
    out.line({nv_text, nf_text, "0"});
    const size_t per_vertex = 3 + (h.normals ? 3 : 0) + (h.texcoords ? 2 : 0);
    for (long long v = 0; v < nv; ++v) {
        if (!in.line(words)) fail(path, in.line_number(), "the file ends after " + std::to_string(v) + " of " + std::to_string(nv) + " vertices");
        if (words.size() < per_vertex) fail(path, in.last_line(), "vertex " + std::to_string(v) + " has " + std::to_string(words.size()) + " numbers, expected at least " + std::to_string(per_vertex));
        for (std::string_view w : words)
            if (!parse_number(w)) fail(path, in.last_line(), "vertex " + std::to_string(v) + ": " + quoted(w) + " is not a number");
        // a colour (3 or 4 values) only where the keyword announces one; other values are dropped
        const size_t extra = words.size() - per_vertex;
        if (h.colors && extra != 3 && extra != 4)
            fail(path, in.last_line(), "vertex " + std::to_string(v) + ": " + std::to_string(extra) + " values after its " + std::to_string(per_vertex) + ", expected a colour of 3 or 4");
        out.line(words, 0, h.colors ? words.size() : per_vertex);
    }
    for (long long f = 0; f < nf; ++f) {
        std::string_view t;
        if (!in.next(t)) fail(path, in.line_number(), "the file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
        const size_t line = in.line_number();
        long long n = 0;
        if (!parse_integer(t, n) || n < 1 || n > nv) fail(path, line, "face " + std::to_string(f) + " announces " + quoted(t) + " corners, the file has " + std::to_string(nv) + " vertices");
        std::vector<std::string_view> face{t};
        for (long long k = 0; k < n; ++k) {
            long long index = 0;
            if (!in.next(t)) fail(path, in.line_number(), "the file ends inside face " + std::to_string(f));
            if (!parse_integer(t, index) || index < 0 || index >= nv)
                fail(path, in.line_number(), "face " + std::to_string(f) + " refers to vertex " + quoted(t) + ", the file has " + std::to_string(nv));
            face.push_back(t);
        }
        if (in.line_number() == line) in.rest_of_line(words);  // a face colour may follow the corners: dropped
        out.line(face, 0, face.size());
    }
}

// ---- PLY --------------------------------------------------------------------------------------

// A PLY scalar type: its size in bytes (0: not a PLY type), whether it is signed and an integer.
struct PlyType {
    int size = 0;
    bool is_signed = false, integer = true;
};

PlyType ply_type(std::string_view t) {
    static const std::map<std::string_view, PlyType> types = {
        {"char", {1, true, true}},     {"int8", {1, true, true}},     {"uchar", {1, false, true}},    {"uint8", {1, false, true}},
        {"short", {2, true, true}},    {"int16", {2, true, true}},    {"ushort", {2, false, true}},   {"uint16", {2, false, true}},
        {"int", {4, true, true}},      {"int32", {4, true, true}},    {"uint", {4, false, true}},     {"uint32", {4, false, true}},
        {"float", {4, false, false}},  {"float32", {4, false, false}}, {"double", {8, false, false}},  {"float64", {8, false, false}}};
    const auto it = types.find(t);
    return it == types.end() ? PlyType{} : it->second;
}

struct PlyProperty {
    std::string name;
    std::string declaration;  // the header line, canonical
    PlyType type;           // scalar type, or the list's item type
    PlyType count;          // size 0 for a scalar
    bool indices = false;   // the face element's vertex_indices list
};
struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
    size_t line = 0;
};

// Checks a PLY file and writes the canonical header into `out`, then the canonical body (ASCII)
// or the body's bytes as they are (binary).
void check_ply(const std::string& path, std::string_view text, Canonical& out) {
    Tokens in(text);
    std::vector<std::string_view> w;
    if (!in.line(w) || w.size() != 1 || w[0] != "ply") fail(path, 1, "expected 'ply' on the first line");
    std::string format;
    std::vector<PlyElement> elements;
    for (;;) {
        if (in.offset() > (size_t(1) << 20)) fail(path, in.line_number(), "no end_header in the first megabyte");
        if (!in.line(w)) fail(path, in.line_number(), "the file ends before end_header");
        const size_t line = in.last_line();
        if (w[0] == "end_header") break;
        if (w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "format") {
            if (!format.empty()) fail(path, line, "a second format line");
            if (w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian") || w[2] != "1.0")
                fail(path, line, "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
            format = std::string(w[1]);
        } else if (w[0] == "element") {
            long long count = 0;
            if (w.size() != 3 || !parse_integer(w[2], count) || count < 0) fail(path, line, "expected 'element NAME COUNT'");
            // OpenMesh reads the count as a 32-bit unsigned: a larger one fails its stream, and its
            // header loop then never meets end_header (memory grows without end)
            if (uint64_t(count) > 0xFFFFFFFFull) fail(path, line, "the element count " + std::string(w[2]) + " exceeds 4294967295");
            elements.push_back({std::string(w[1]), uint64_t(count), {}, line});
        } else if (w[0] == "property") {
            if (elements.empty()) fail(path, line, "a property before any element");
            PlyElement& e = elements.back();
            if (w.size() == 3 && ply_type(w[1]).size > 0) {
                e.properties.push_back({std::string(w[2]), "property " + std::string(w[1]) + " " + std::string(w[2]), ply_type(w[1]), {}, false});
            } else if (w.size() == 5 && w[1] == "list" && ply_type(w[2]).size > 0 && ply_type(w[2]).integer && ply_type(w[3]).size > 0) {
                const bool indices = e.name == "face" && (w[4] == "vertex_indices" || w[4] == "vertex_index");
                e.properties.push_back({std::string(w[4]), "property list " + std::string(w[2]) + " " + std::string(w[3]) + " " + std::string(w[4]), ply_type(w[3]), ply_type(w[2]), indices});
            } else {
                fail(path, line, "expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME' with known types, found " + quoted(w.size() > 1 ? w[1] : w[0]));
            }
        } else {
            // other lines (an exporter's note without 'comment') are skipped, as OpenMesh does,
            // but its header parser reads words, not lines: a keyword after unknown words ("x
            // element ..."), and a format or type word there makes it loop: such a line is an error
            for (size_t k = 1; k < w.size(); ++k)
                if (w[k] == "element" || w[k] == "property" || w[k] == "format" || w[k] == "end_header" || w[k] == "ply" || w[k] == "list" ||
                    w[k] == "ascii" || w[k] == "binary_little_endian" || w[k] == "binary_big_endian" || ply_type(w[k]).size > 0)
                    fail(path, line, "a header line starting with " + quoted(w[0]) + " has the keyword " + quoted(w[k]) + " after it (expected format, element, property, comment, obj_info or end_header first)");
        }
    }
    if (format.empty()) fail(path, in.line_number(), "the header has no format line");
    out.line({"ply"});
    out.line({"format", format, "1.0"});
    for (const PlyElement& e : elements) {
        out.line({"element", e.name, std::to_string(e.count)});
        for (const PlyProperty& p : e.properties) out.line({p.declaration});
    }
    out.line({"end_header"});
    uint64_t vertices = 0;
    for (const PlyElement& e : elements)
        if (e.name == "vertex") vertices = e.count;
    for (const PlyElement& e : elements)
        if (e.name == "face" && e.count > 0 && vertices == 0) fail(path, e.line, "faces without a vertex element before them");
    if (format == "ascii") {
        for (const PlyElement& e : elements) {
            // one instance per line; counts bounded by the lines the file can hold
            if (e.count > text.size() / 2) fail(path, e.line, std::to_string(e.count) + " " + e.name + " elements cannot fit in a file of " + std::to_string(text.size()) + " bytes");
            for (uint64_t i = 0; i < e.count; ++i) {
                if (!in.line(w)) fail(path, in.line_number(), "the file ends after " + std::to_string(i) + " of " + std::to_string(e.count) + " " + e.name + " elements");
                const size_t line = in.last_line();
                size_t k = 0;
                for (const PlyProperty& p : e.properties) {
                    if (k >= w.size()) fail(path, line, e.name + " " + std::to_string(i) + ": no value for " + p.name);
                    if (p.count.size == 0) {
                        long long integer = 0;  // an integer property read as a float would shift every later value
                        if (p.type.integer ? !parse_integer(w[k], integer) : !parse_number(w[k]))
                            fail(path, line, e.name + " " + std::to_string(i) + ": " + quoted(w[k]) + " is not " + (p.type.integer ? "an integer" : "a number"));
                        ++k;
                        continue;
                    }
                    long long n = 0;
                    if (!parse_integer(w[k++], n) || n < 0 || uint64_t(n) > w.size() - k)
                        fail(path, line, e.name + " " + std::to_string(i) + ": the list " + p.name + " announces " + quoted(w[k - 1]) + " items, the line holds " + std::to_string(w.size() - k));
                    for (long long j = 0; j < n; ++j, ++k) {
                        long long index = 0;
                        if (p.indices ? !parse_integer(w[k], index) || index < 0 || uint64_t(index) >= vertices : !parse_number(w[k]))
                            fail(path, line, e.name + " " + std::to_string(i) + ": " + quoted(w[k]) + (p.indices ? " is not a vertex of the " + std::to_string(vertices) : " is not a number"));
                    }
                }
                // OpenMesh reads values, not lines: one value too many shifts every later one
                // (a face's corner count read from a vertex's extra value)
                if (k < w.size())
                    fail(path, line, e.name + " " + std::to_string(i) + ": " + std::to_string(w.size() - k) + " value" + (w.size() - k > 1 ? "s" : "") +
                                         " past its " + std::to_string(e.properties.size()) + " propert" + (e.properties.size() > 1 ? "ies" : "y") + ", from " + quoted(w[k]));
                out.line(w, 0, w.size());
            }
        }
        return;
    }
    // binary: walk the elements by their sizes, reading list counts (and face indices)
    const bool little = format == "binary_little_endian";
    size_t at = in.offset();
    out.text.append(text.substr(at));  // after the canonical header, the body as it is
    auto read = [&](PlyType type, double& value) {  // an integer's value (a float's is not needed)
        if (at + size_t(type.size) > text.size()) return false;
        uint8_t b[8];
        std::memcpy(b, text.data() + at, size_t(type.size));
        at += size_t(type.size);
        if (!little) std::reverse(b, b + type.size);
        uint64_t u = 0;
        std::memcpy(&u, b, size_t(type.size));
        if (type.is_signed && type.size < 8 && (u >> (8 * type.size - 1)) & 1) u |= ~uint64_t(0) << (8 * type.size);  // sign-extend
        value = type.is_signed ? double(int64_t(u)) : double(u);
        return true;
    };
    for (const PlyElement& e : elements) {
        uint64_t fixed = 0;  // bytes of the scalars and list counts
        bool scalars_only = true;
        for (const PlyProperty& p : e.properties) {
            fixed += uint64_t(p.count.size > 0 ? p.count.size : p.type.size);
            scalars_only &= p.count.size == 0;
        }
        if (fixed > 0 && e.count > (text.size() - at) / fixed)
            fail(path, e.line, std::to_string(e.count) + " " + e.name + " elements of at least " + std::to_string(fixed) + " bytes cannot fit in the " + std::to_string(text.size() - at) + " bytes left");
        if (fixed == 0 && e.count > text.size())
            fail(path, e.line, std::to_string(e.count) + " " + e.name + " elements without properties in a file of " + std::to_string(text.size()) + " bytes");
        if (scalars_only) {
            at += size_t(fixed * e.count);
            continue;
        }
        for (uint64_t i = 0; i < e.count; ++i)
            for (const PlyProperty& p : e.properties) {
                if (p.count.size == 0) {  // a scalar
                    if (at + size_t(p.type.size) > text.size()) fail(path, e.line, "the data ends inside " + e.name + " " + std::to_string(i));
                    at += size_t(p.type.size);
                    continue;
                }
                double n = 0;
                if (!read(p.count, n)) fail(path, e.line, "the data ends inside " + e.name + " " + std::to_string(i));
                const uint64_t item = uint64_t(p.type.size);
                if (n < 0 || uint64_t(n) > (text.size() - at) / item)
                    fail(path, e.line, e.name + " " + std::to_string(i) + ": the list " + p.name + " announces " + std::to_string(int64_t(n)) + " items, the file holds fewer");
                if (!p.indices) {
                    at += size_t(uint64_t(n) * item);
                    continue;
                }
                for (uint64_t j = 0; j < uint64_t(n); ++j) {
                    double index = 0;
                    read(p.type, index);
                    if (index < 0 || index >= double(vertices))
                        fail(path, e.line, e.name + " " + std::to_string(i) + " refers to vertex " + std::to_string(int64_t(index)) + ", the file has " + std::to_string(vertices));
                }
            }
    }
}

// ---- OBJ --------------------------------------------------------------------------------------

// Checks an OBJ file and writes the canonical text into `out`: v, vt, vn and f lines only, the
// values as OpenMesh's stream would read them, the indices absolute.
void check_obj(const std::string& path, std::string_view text, Canonical& out, ObjGroups* groups) {
    // totals first: OpenMesh reads every v, vt and vn before the faces
    uint64_t v = 0, vt = 0, vn = 0;
    {
        Tokens in(text);
        std::vector<std::string_view> w;
        while (in.line(w)) {
            if (w[0] == "v") ++v;
            else if (w[0] == "vt") ++vt;
            else if (w[0] == "vn") ++vn;
        }
    }
    Tokens in(text);
    std::vector<std::string_view> w;
    // an OBJ index: 1-based, or negative from the end of what is defined so far
    uint64_t seen_v = 0, seen_vt = 0, seen_vn = 0;
    int32_t material = -1;
    if (groups) groups->face_first.assign(1, 0);
    // the index as an absolute, 1-based number
    auto check_index = [&](std::string_view s, uint64_t total, uint64_t seen, const char* what, size_t line) {
        long long i = 0;
        if (!parse_integer(s, i) || i == 0 || (i > 0 && uint64_t(i) > total) || (i < 0 && uint64_t(-i) > seen))
            fail(path, line, std::string("a face refers to ") + what + " " + quoted(s) + ", the file has " + std::to_string(total));
        return std::to_string(i > 0 ? uint64_t(i) : seen + 1 - uint64_t(-i));
    };
    while (in.line(w)) {
        const size_t line = in.last_line();
        // values are OpenMesh's to read (it takes what parses, as "3.1+e2" -> 3.1); indices are
        // what it would follow out of bounds
        // a v, vt or vn line whose numbers do not read adds nothing in OpenMesh, while the counts
        // above (and every later index) took it: such a line is an error
        // (the stream reads the line's values one after another: only the last may carry a
        // suffix, which the stream leaves unread, as "3.1+e2" reads 3.1; "1o" before another
        // value makes that value's read fail)
        // the line's first `count` numbers, the last as far as it reads
        auto numbers = [&](size_t count, const char* what) {
            std::vector<std::string_view> values{w[0]};
            for (size_t k = 1; k <= count; ++k) {
                size_t used = 0;
                if (k >= w.size() || !parse_number(w[k], k == count, &used))
                    fail(path, line, std::string(what) + " needs " + std::to_string(count) + " numbers, found " + (k < w.size() ? quoted(w[k]) : "the end of the line"));
                values.push_back(w[k].substr(0, used));
            }
            out.line(values, 0, values.size());
        };
        if (w[0] == "v") {
            // a colour after the position (v x y z r g b) when all six are numbers
            bool colour = w.size() == 7;
            for (size_t k = 1; k < w.size() && colour; ++k) colour = parse_number(w[k]);
            if (colour) out.line(w, 0, w.size());
            else numbers(3, "a vertex");
            ++seen_v;
        } else if (w[0] == "vt") {
            numbers(2, "a texture coordinate");
            ++seen_vt;
        } else if (w[0] == "vn") {
            numbers(3, "a normal");
            ++seen_vn;
        } else if (groups && (w[0] == "usemtl" || w[0] == "mtllib") && w.size() >= 2) {
            // names may hold spaces: the rest of the line, its words joined by one space
            std::string name(w[1]);
            for (size_t k = 2; k < w.size(); ++k) name += " " + std::string(w[k]);
            if (w[0] == "mtllib") {
                groups->libraries.push_back(name);
                continue;
            }
            const auto known = std::find(groups->materials.begin(), groups->materials.end(), name);
            material = int32_t(known - groups->materials.begin());
            if (known == groups->materials.end()) groups->materials.push_back(name);
        } else if (w[0] == "f") {
            std::string face = "f";
            const size_t first_vertex = groups ? groups->face_vertices.size() : 0;
            for (size_t k = 1; k < w.size(); ++k) {
                const std::string_view c = w[k];
                const size_t s1 = c.find('/');
                const std::string vertex = check_index(c.substr(0, s1), v, seen_v, "vertex", line);
                face += " " + vertex;
                if (groups) groups->face_vertices.push_back(uint32_t(std::stoull(vertex) - 1));
                if (s1 == std::string_view::npos) continue;
                const size_t s2 = c.find('/', s1 + 1);
                const std::string_view t = c.substr(s1 + 1, s2 == std::string_view::npos ? std::string_view::npos : s2 - s1 - 1);
                face += "/";
                if (!t.empty()) face += check_index(t, vt, seen_vt, "texture coordinate", line);
                if (s2 != std::string_view::npos) face += "/" + check_index(c.substr(s2 + 1), vn, seen_vn, "normal", line);
            }
            if (w.size() >= 4) {  // fewer than three corners make no face
                out.line({face});
                if (groups) {
                    groups->face_first.push_back(uint32_t(groups->face_vertices.size()));
                    groups->face_material.push_back(material);
                }
            } else if (groups) {
                groups->face_vertices.resize(first_vertex);
            }
        }
    }
}

// ---- STL --------------------------------------------------------------------------------------

// OpenMesh takes a file whose first line starts with "solid" as ASCII, and any other as binary
// when its size is 84 + 50 x the triangle count. In ASCII, every line with "outer" is followed
// by three vertex lines it reads as a word and three numbers, and a "facet normal" line gives
// three numbers: a line that is missing or does not parse leaves values uninitialised.
void check_stl(const std::string& path, std::string_view text, Canonical& out) {
    // OpenMesh looks at the first non-empty line for "solid" past its spaces and tabs, and reads
    // out of bounds when there is nothing else on it
    size_t start = 0, first_line = 1;
    while (start < text.size() && text[start] == '\n') ++start, ++first_line;
    const size_t end = std::min(text.find('\n', start), text.size());
    const size_t first = text.substr(start, end - start).find_first_not_of(" \t");
    if (first == std::string_view::npos) fail(path, first_line, "the first line holds nothing but blanks");
    start += first;
    const bool ascii = text.size() - start >= 5 && strncasecmp(text.data() + start, "solid", 5) == 0;
    if (!ascii) {
        // binary: an 80-byte header, the triangle count, 50 bytes per triangle (the values
        // themselves are cleaned later)
        uint32_t n = 0;
        if (text.size() >= 84) std::memcpy(&n, text.data() + 80, 4);
        if (text.size() < 84 || uint64_t(text.size()) != 84 + 50 * uint64_t(n))
            fail(path, 1, "neither ASCII STL (starting with 'solid') nor binary STL (84 bytes and 50 per triangle: " + std::to_string(n) + " triangles would take " +
                              std::to_string(84 + 50 * uint64_t(n)) + " bytes, the file has " + std::to_string(text.size()) + ")");
        return;
    }
    Tokens in(text);
    std::vector<std::string_view> w;
    out.line({"solid", "tom"});
    std::vector<std::string_view> normal{"facet", "normal", "0", "0", "0"};
    std::string normal_text;
    while (in.line(w)) {
        if (w.size() >= 2 && w[0] == "facet" && w[1] == "normal") {
            if (w.size() < 5 || !parse_number(w[2]) || !parse_number(w[3]) || !parse_number(w[4])) fail(path, in.last_line(), "expected 'facet normal X Y Z'");
            normal_text = std::string(w[2]) + " " + std::string(w[3]) + " " + std::string(w[4]);
        }
        bool outer = false;
        for (std::string_view t : w) outer |= t.find("outer") != std::string_view::npos || t.find("OUTER") != std::string_view::npos;
        if (!outer) continue;
        const size_t line = in.last_line();
        out.line({"facet normal", normal_text.empty() ? "0 0 0" : normal_text});
        out.line({"outer loop"});
        for (int k = 0; k < 3; ++k) {
            in.rest_of_line(w);
            if (w.size() < 4 || !parse_number(w[1]) || !parse_number(w[2]) || !parse_number(w[3]))
                fail(path, line + 1 + size_t(k), "expected 'vertex X Y Z' (corner " + std::to_string(k + 1) + " of the facet opened on line " + std::to_string(line) + ")");
            out.line({"vertex", w[1], w[2], w[3]});
        }
        out.line({"endloop"});
        out.line({"endfacet"});
        normal_text.clear();
    }
    out.line({"endsolid", "tom"});
}

} // namespace

std::string check_mesh_file(const std::string& path, const std::string& extension, ObjGroups* groups) {
    if (extension != "off" && extension != "ply" && extension != "obj" && extension != "stl") return {};
    const std::vector<uint8_t> bytes = read_whole_file(path);
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    Canonical out;
    if (extension == "off") check_off(path, text, out);
    else if (extension == "ply") check_ply(path, text, out);
    else if (extension == "stl") check_stl(path, text, out);
    else check_obj(path, text, out, groups);
    return std::move(out.text);
}

} // namespace tom::detail
