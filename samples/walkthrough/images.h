#pragma once
// The base-colour images of a .tom file's parts, for the headless renderer: an image stored in
// the file (embedded in the source asset), or an image file beside it as the source named it.
// Shared by tomview and tcrwalk.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "renderer.h"
#include "tom/format.h"

namespace walk {

/// A part's base-colour image: stored in its .tom (`stored`), or a file (`key`, its path); `key`
/// names it for load_image's cache, and is empty when the part has none.
struct PartImage {
    std::string key;
    const tom::Image* stored = nullptr;
};

/// The base-colour image (TEXCOORD_0) of each part of mesh `mesh` of `file`, whose path is
/// `tom_path`: the stored image, or the file the texture's URI names relative to the .tom ('\\'
/// read as '/'). A file that is not there is reported on stderr and its part has none.
std::vector<PartImage> find_part_images(const tom::File& file, uint32_t mesh, const std::filesystem::path& tom_path);

/// The renderer's handle of `image`, loaded once per key into `loaded`; -1 for a part without one.
/// \throw std::runtime_error when the image cannot be decoded (naming it).
int32_t load_image(const PartImage& image, Renderer& renderer, std::map<std::string, int32_t>& loaded);

} // namespace walk
