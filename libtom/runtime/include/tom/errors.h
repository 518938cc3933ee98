#pragma once
// Errors reported by libtom's libraries and libtcr. They never print: every problem with data
// from outside (files, meshes handed in by a caller) and every argument that breaks a documented
// precondition on data is thrown as one of these, with a one-line message that names the file,
// the place and the problem. Catching tom::Error catches them all.

#include <cstdint>
#include <stdexcept>
#include <string>

namespace tom {

/// Base of every error libtom throws for bad data. what() is a complete,
/// one-line message suitable for printing as is.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// A .tom file (or byte buffer) that does not satisfy docs/FORMAT.md.
/// path() is the file ("<memory>" for a buffer), offset() the byte offset of the
/// offending field, field() its name as FORMAT.md spells it, rule() the number
/// of the validation rule in FORMAT.md that failed.
class FormatError : public Error {
public:
    FormatError(std::string path, uint64_t offset, std::string field, int rule, const std::string& detail);
    const std::string& path() const noexcept { return path_; }
    uint64_t offset() const noexcept { return offset_; }
    const std::string& field() const noexcept { return field_; }
    int rule() const noexcept { return rule_; }

private:
    std::string path_;
    uint64_t offset_;
    std::string field_;
    int rule_;
};

/// A mesh file (OBJ, PLY, OFF, STL, glTF) that cannot be imported, or a mesh
/// whose content is unusable (an index out of range, a non-finite position).
/// One name in every language: tom::MeshError, Python's tom.MeshError, C's TOM_ERROR_MESH.
class MeshError : public Error {
public:
    using Error::Error;
};
using ImportError = MeshError;  ///< its former name

/// An I/O failure that is not about content: cannot open, cannot write, cannot rename.
class IoError : public Error {
public:
    using Error::Error;
};

/// A text file that does not parse (a libtcr calibration file); the message names the file and
/// the line.
class ParseError : public Error {
public:
    using Error::Error;
};

/// Arguments that break a function's documented precondition on their content (a surface
/// without triangles, meshes that do not belong together, an instance naming a missing mesh).
class ArgumentError : public Error {
public:
    using Error::Error;
};

/// A broken internal invariant (a built order that is not one): a bug in the library, never the
/// caller's data; the message says what broke. Please report it.
class InternalError : public Error {
public:
    using Error::Error;
};

} // namespace tom
