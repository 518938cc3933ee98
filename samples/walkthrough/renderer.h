#pragma once
// A headless OpenGL renderer on Mesa's OSMesa (llvmpipe, the CPU rasterizer): what the
// walkthrough draws with. Vertex buffers are uploaded once per mesh; each frame the chosen
// levels' index buffers are streamed into one index buffer and drawn with one indexed draw per
// object (or part): Gouraud shading with two directional lights, as in the papers, or flat
// shading (each triangle lit by its provoking vertex's normal); and imposters, each a texture
// the frame's captures render objects into through a framebuffer object, drawn with an alpha
// test as one quad (simple) or over a grid mesh of the capture's depth buffer (meshed).

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

    /// Uploads a mesh's full vertex streams (positions, normals, texture coordinates); returns its handle.
    uint32_t add_mesh(const tom::MeshView& mesh);
    /// Loads an image (PNG, JPEG, ...: stb_image) as a mipmapped, repeating texture for textured
    /// draws; returns its handle. \throw std::runtime_error naming the file and stb_image's reason.
    uint32_t add_image(const std::string& path);
    /// The same from an encoded image in memory (an image stored in a .tom); `name` stands for it
    /// in messages. \throw std::runtime_error naming it and stb_image's reason.
    uint32_t add_image(const uint8_t* encoded, size_t bytes, const std::string& name);
    /// The same from RGBA pixels in memory (rows in the order of texture coordinate v, from 0).
    uint32_t add_image(uint32_t width, uint32_t height, const unsigned char* rgba);

    enum class Shading : uint8_t { smooth, flat, imposter, meshed, textured };
    struct Draw {
        uint32_t mesh;
        const float* model;  ///< 4x4 column-major
        size_t first;        ///< offset of the object's indices in the frame's index array
        uint32_t index_count;
        float color[3];
        Shading shading = Shading::smooth;
        int32_t capture = -1;   ///< >= 0: drawn into that capture's texture instead of the frame (skipped when the frame has no such capture)
        uint32_t texture = 0;   ///< imposters: the texture slot their quad or depth mesh shows
        float corners[12] = {}; ///< simple imposters: the quad's corners in world space, texture (0,0), (1,0), (1,1), (0,1)
        float tint = 0;         ///< imposters: how much of `color` to mix into the texture's
        uint32_t tag = 0;       ///< the caller's (the walkthrough: its object), unused here
        uint32_t image = 0;     ///< textured draws: the image (add_image) its Gouraud shade is multiplied by
    };
    /// A render of objects into a texture slot (a square of side x side, a power of two from 16 to
    /// 256, in a layer of an array texture that the frame's imposters share), before the frame.
    struct Capture {
        uint32_t texture;
        uint32_t side;
        float view[16], projection[16];
        /// > 0: a meshed imposter's capture; its depth is read back into a mesh of grid x grid
        /// cells (tcr::depth_mesh) that the slot's meshed draws show until its next capture
        uint32_t grid = 0;
    };
    /// Renders the captures into their textures (the draws marked with their index), then clears
    /// the frame, draws the rest, imposters last, and waits for the rasterizer (glFinish). The
    /// frame's indices are uploaded once, into one buffer. Matrices column-major.
    void render(const float view[16], const float projection[16], const std::vector<Draw>& draws, const std::vector<uint32_t>& indices,
                size_t index_count, const std::vector<Capture>& captures = {});
    /// Bytes of the imposter textures held (the array textures' whole layers).
    size_t texture_bytes() const noexcept;
    /// The frame as drawn: RGBA, 8 bits a channel, rows from the bottom.
    std::vector<unsigned char> read_pixels() const;
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
