#pragma once
// A headless OpenGL renderer on Mesa's OSMesa (llvmpipe, the CPU rasterizer): what the
// walkthrough draws with. Vertex buffers are uploaded once per mesh; each frame the chosen
// levels' index buffers are streamed into one index buffer and drawn with one indexed draw per
// object; Gouraud shading with two directional lights, as in the papers.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tom/view.h"

namespace walk {

class Renderer {
public:
    /// \throw std::runtime_error when no OSMesa OpenGL 3.3 core context can be created.
    Renderer(uint32_t width, uint32_t height);
    ~Renderer();

    /// Uploads a mesh's full vertex streams (positions, normals); returns its handle.
    uint32_t add_mesh(const tom::MeshView& mesh);

    struct Draw {
        uint32_t mesh;
        const float* model;  ///< 4x4 column-major
        size_t first;        ///< offset of the object's indices in the frame's index array
        uint32_t index_count;
        float color[3];
    };
    /// Clears, uploads the frame's indices (one buffer), draws every object with one indexed draw,
    /// waits for the rasterizer (glFinish). view/projection column-major.
    void render(const float view[16], const float projection[16], const std::vector<Draw>& draws, const std::vector<uint32_t>& indices,
                size_t index_count);
    /// Reads the frame back and writes it as PNG. \return false when the file cannot be written.
    bool save_png(const std::string& path);
    uint32_t width() const noexcept { return width_; }
    uint32_t height() const noexcept { return height_; }
    std::string description() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    uint32_t width_, height_;
};

} // namespace walk
