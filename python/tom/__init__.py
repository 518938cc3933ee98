"""Totally Ordered Meshes: level of detail from one sorted mesh.

    import tom
    f = tom.open("bunny00.tom")            # mapped and validated
    mesh = f.meshes[0]
    mesh.positions                         # (n, 3) float32 view into the file, read-only
    indices, n = mesh.extract(fraction=0.1)  # a level: draw vertices [0, n) with indices

Building: tom.build(positions, triangles) or tom.build(tom.import_file(path)[0]), then
tom.write(path, [built]); tom.report(original, built) measures it as tombuild's JSON report.
Errors are tom.Error subclasses carrying the library's one-line message.
"""

from ._tom import (
    ArgumentError,
    BuiltMesh,
    Error,
    File,
    FileMesh,
    FormatError,
    IoError,
    Mesh,
    MeshError,
    ParseError,
    build,
    format_version,
    import_file,
    open,
    open_bytes,
    report,
    serialize,
    write,
)
from ._tom import tcr

MeshFileError = MeshError  # its former name

__all__ = [
    "ArgumentError", "BuiltMesh", "Error", "File", "FileMesh", "FormatError", "IoError", "Mesh", "MeshError", "MeshFileError", "ParseError",
    "build", "format_version", "import_file", "open", "open_bytes", "report", "serialize", "tcr", "write",
]
