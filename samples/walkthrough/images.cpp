// The parts' base-colour images: stored in the .tom or beside it (images.h).

#include "images.h"

#include <algorithm>
#include <cstdio>

namespace walk {

std::vector<PartImage> find_part_images(const tom::File& file, uint32_t mesh_index, const std::filesystem::path& tom_path) {
    const tom::MeshView& mesh = file.mesh(mesh_index);
    const tom::Scene& scene = file.scene();
    std::vector<PartImage> images(tom::part_count(mesh));
    for (uint32_t p = 0; p < images.size(); ++p) {
        const int32_t material = tom::part_at(mesh, p).material;
        if (material < 0 || size_t(material) >= scene.materials.size()) continue;
        for (const tom::TextureRef& t : scene.materials[size_t(material)].textures) {
            if (t.role != tom::TextureRole::base_color || t.texcoord != 0) continue;
            if (t.image >= 0) {
                images[p].stored = &scene.images[size_t(t.image)];
                images[p].key = tom_path.string() + "#" + std::to_string(t.image);
                continue;
            }
            if (t.uri.empty()) continue;
            std::string uri = t.uri;
            std::replace(uri.begin(), uri.end(), '\\', '/');
            const std::filesystem::path path = (tom_path.parent_path() / uri).lexically_normal();
            if (std::filesystem::exists(path)) images[p].key = path.string();
            else std::fprintf(stderr, "warning: %s: part %u's image '%s' is not at %s; drawn without it\n", tom_path.string().c_str(), p, t.uri.c_str(), path.string().c_str());
        }
    }
    return images;
}

int32_t load_image(const PartImage& image, Renderer& renderer, std::map<std::string, int32_t>& loaded) {
    if (image.key.empty()) return -1;
    auto it = loaded.find(image.key);
    if (it == loaded.end())
        it = loaded.emplace(image.key, int32_t(image.stored ? renderer.add_image(image.stored->data, size_t(image.stored->bytes), image.key) : renderer.add_image(image.key)))
                 .first;
    return it->second;
}

} // namespace walk
