#pragma once
// What the C API's translation units share (tom_c.cpp, tcr_c.cpp): this thread's last error,
// the exceptions-to-status guard and the library view behind a tom_mesh_view.

#include <exception>
#include <new>
#include <string>

#include "tom/errors.h"
#include "tom/tom.h"
#include "tom/view.h"

namespace tom::capi {

/// Records `message` as this thread's last error; returns `status`.
tom_status fail(tom_status status, const std::string& message);
/// TOM_ERROR_ARGUMENT: "function: argument is NULL".
tom_status null_argument(const char* function, const char* argument);

/// Runs `body`, which returns a tom_status, turning each exception into its status.
template <class Body>
tom_status guarded(Body&& body) noexcept {
    try {
        return body();
    } catch (const tom::FormatError& e) {
        return fail(TOM_ERROR_FORMAT, e.what());
    } catch (const tom::IoError& e) {
        return fail(TOM_ERROR_IO, e.what());
    } catch (const tom::MeshError& e) {
        return fail(TOM_ERROR_MESH, e.what());
    } catch (const tom::ArgumentError& e) {
        return fail(TOM_ERROR_ARGUMENT, e.what());
    } catch (const tom::ParseError& e) {
        return fail(TOM_ERROR_PARSE, e.what());
    } catch (const std::bad_alloc&) {
        return fail(TOM_ERROR_MEMORY, "out of memory");
    } catch (const std::exception& e) {
        return fail(TOM_ERROR_INTERNAL, e.what());
    } catch (...) {
        return fail(TOM_ERROR_INTERNAL, "unknown error");
    }
}

/// The library's view behind a filled tom_mesh_view; null for a null or unfilled one.
inline const tom::MeshView* view_of(const tom_mesh_view* mesh) { return mesh ? static_cast<const tom::MeshView*>(mesh->internal) : nullptr; }

} // namespace tom::capi
