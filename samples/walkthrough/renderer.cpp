// OSMesa OpenGL 3.3 core renderer for the walkthrough.

#define GL_GLEXT_PROTOTYPES
#include "renderer.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <initializer_list>
#include <stdexcept>
#include <string>

#include "tcr/runtime.h"
#include "tcr/view.h"

namespace walk {

namespace {

// The mesh shaders, one source for Funkhouser & Sequin's three rendering algorithms, chosen by
// the defines in front of it (with_defines): SHADE is the shade's interpolation qualifier, empty
// for Gouraud shading or "flat" for the provoking vertex's shade over the whole triangle;
// TEXTURED multiplies the Gouraud shade by the image at the vertex's texture coordinates.
const char* kVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
#ifdef TEXTURED
layout(location = 2) in vec2 texcoord;
out vec2 uv;
#endif
uniform mat4 model;
uniform mat4 view_projection;
uniform vec3 color;
SHADE out vec3 shade;
void main() {
    vec3 n = normalize(mat3(model) * normal);
    // two directional lights and an ambient term, lit per vertex
    float d = 0.15 + 0.65 * max(dot(n, normalize(vec3(0.4, 0.8, 0.5))), 0.0) + 0.3 * max(dot(n, normalize(vec3(-0.6, 0.2, -0.4))), 0.0);
    shade = color * d;
#ifdef TEXTURED
    uv = texcoord;
#endif
    gl_Position = view_projection * model * vec4(position, 1.0);
}
)";

const char* kFragment = R"(
SHADE in vec3 shade;
#ifdef TEXTURED
in vec2 uv;
uniform sampler2D image;
#endif
out vec4 frag;
void main() {
#ifdef TEXTURED
    frag = vec4(shade * texture(image, uv).rgb, 1.0);
#else
    frag = vec4(shade, 1.0);
#endif
}
)";

// The imposters' vertex shader. A simple imposter (no define) is one quad from four corners,
// an instance of a four-vertex strip (gl_VertexID 0..3); a meshed imposter (MESHED) is its depth
// mesh's vertices in world space, each with its texture point in the capture. Either way the
// capture's cell, colour and tint and layer come with each instance or vertex, so a chunk's
// imposters are one draw.
const char* kImposterVertex = R"(
#ifdef MESHED
layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv_in;
layout(location = 2) in vec4 cell_in;
layout(location = 3) in vec4 look_in;
layout(location = 4) in float layer_in;
#else
layout(location = 0) in vec3 c0;
layout(location = 1) in vec3 c1;
layout(location = 2) in vec3 c2;
layout(location = 3) in vec3 c3;
layout(location = 4) in vec4 cell_in;   // the capture's square in its layer: origin, side, half a texel (texture units)
layout(location = 5) in vec4 look_in;   // colour, tint
layout(location = 6) in float layer_in;
#endif
uniform mat4 view_projection;
out vec2 uv;
flat out vec4 cell;
flat out vec4 look;
flat out float layer;
void main() {
    cell = cell_in;
    look = look_in;
    layer = layer_in;
#ifdef MESHED
    uv = uv_in;
    gl_Position = view_projection * vec4(position, 1.0);
#else
    const int corner[4] = int[4](0, 1, 3, 2);
    const vec2 uvs[4] = vec2[4](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 1));
    vec3 corners[4] = vec3[4](c0, c1, c2, c3);
    int c = corner[gl_VertexID];
    uv = uvs[c];
    gl_Position = view_projection * vec4(corners[c], 1.0);
#endif
}
)";

// Both imposters' fragments: the capture's texel, clamped to its cell, alpha-tested.
const char* kImposterFragment = R"(
in vec2 uv;
flat in vec4 cell;
flat in vec4 look;
flat in float layer;
uniform sampler2DArray image;
out vec4 frag;
void main() {
    vec2 at = cell.xy + clamp(uv * cell.z, vec2(cell.w), vec2(cell.z - cell.w));  // no texel of a neighbour
    vec4 c = texture(image, vec3(at, layer));
    if (c.a < 0.5) discard;
    frag = vec4(mix(c.rgb, look.rgb, look.a), 1.0);
}
)";

constexpr float kBackground[3] = {0.92f, 0.93f, 0.95f};

GLuint compile(GLenum type, const char* src) {
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024];
        glGetShaderInfoLog(s, sizeof log, nullptr, log);
        throw std::runtime_error(std::string("shader: ") + log);
    }
    return s;
}

GLuint link(const std::string& vertex, const std::string& fragment) {
    const GLuint program = glCreateProgram();
    glAttachShader(program, compile(GL_VERTEX_SHADER, vertex.c_str()));
    glAttachShader(program, compile(GL_FRAGMENT_SHADER, fragment.c_str()));
    glLinkProgram(program);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("OpenGL: cannot link the shaders");
    return program;
}

// A shader source behind "#version 330 core" and its defines (each "NAME" or "NAME VALUE").
std::string with_defines(const char* source, std::initializer_list<const char*> defines) {
    std::string s = "#version 330 core\n";
    for (const char* d : defines) s += std::string("#define ") + d + "\n";
    return s + source;
}

} // namespace

struct Renderer::Impl {
    OSMesaContext context = nullptr;
    std::vector<unsigned char> color;
    struct MeshProgram {
        GLuint program = 0;
        GLint u_model = -1, u_vp = -1, u_color = -1;
    } smooth, flat, textured;
    GLint u_textured_image = -1;
    std::vector<GLuint> images;
    GLuint imposter_program = 0, vao = 0, quad_vao = 0, quad_instances = 0, index_buffer = 0;
    GLint u_imposter_vp = -1, u_image = -1;
    static constexpr int kInstanceFloats = 12 + 4 + 4 + 1;  // corners, cell, colour and tint, layer
    std::vector<float> instances;  // a chunk's imposters, kInstanceFloats each
    GLuint framebuffer = 0, depth = 0;
    // Meshed imposters: each slot's depth mesh, (grid + 1)^2 world positions, from its last capture
    struct DepthMesh {
        uint32_t grid = 0;  // 0: none (the slot's last capture was a simple imposter's)
        std::vector<float> positions;
    };
    std::vector<DepthMesh> depth_meshes;  // by slot
    std::vector<float> depth_texels;      // a capture's depth, read back
    GLuint meshed_program = 0, meshed_vao = 0, meshed_vertices = 0, meshed_indices = 0;
    GLint u_meshed_vp = -1, u_meshed_image = -1;
    static constexpr int kMeshedFloats = 3 + 2 + 4 + 4 + 1;  // position, texture point, cell, colour and tint, layer
    std::vector<float> meshed_vertex_data;
    std::vector<uint32_t> meshed_index_data;
    struct Mesh {
        GLuint vbo;
    };
    std::vector<Mesh> meshes;
    // Imposter textures: square cells of power-of-two sides in the layers of 2D array textures
    // (chunks of kChunkLayers layers of kPageSide square), so a frame's imposters bind one
    // texture per chunk, not one each (binding a texture per quad costs llvmpipe about fifty
    // times the quad). A slot keeps its cell until it needs another side; a cell freed is reused
    // whole, at its side.
    static constexpr uint32_t kPageSide = 256, kChunkLayers = 32, kMinCell = 16, kLevels = 5;  // cells of 16 to 256
    struct Cell {
        uint32_t chunk = 0, layer = 0, x = 0, y = 0, side = 0;  // side 0: none
    };
    std::vector<GLuint> chunks;
    uint32_t layers_used = 0;
    std::vector<Cell> cells;                  // by slot
    std::vector<Cell> free_cells[kLevels];    // by log2(side / kMinCell)

    // a mesh program for one rendering algorithm (the defines of kVertex and kFragment)
    MeshProgram make_mesh_program(std::initializer_list<const char*> defines) {
        MeshProgram p;
        p.program = link(with_defines(kVertex, defines), with_defines(kFragment, defines));
        p.u_model = glGetUniformLocation(p.program, "model");
        p.u_vp = glGetUniformLocation(p.program, "view_projection");
        p.u_color = glGetUniformLocation(p.program, "color");
        return p;
    }
    static uint32_t level_of(uint32_t side) {
        uint32_t level = 0;
        while (level + 1 < kLevels && (kMinCell << level) < side) ++level;
        return level;
    }
    // A free cell of `level`: a free one of that side, else one of a larger side split in four
    // (three go free), else a new layer (and a new chunk when the last is full).
    Cell take_cell(uint32_t level) {
        if (!free_cells[level].empty()) {
            const Cell c = free_cells[level].back();
            free_cells[level].pop_back();
            return c;
        }
        if (level + 1 == kLevels) {
            if (layers_used == chunks.size() * kChunkLayers) chunks.push_back(new_chunk());
            const uint32_t layer = layers_used++;
            return Cell{layer / kChunkLayers, layer % kChunkLayers, 0, 0, kPageSide};
        }
        const Cell big = take_cell(level + 1);
        const uint32_t half = big.side / 2;
        for (uint32_t q = 3; q >= 1; --q) free_cells[level].push_back(Cell{big.chunk, big.layer, big.x + half * (q % 2), big.y + half * (q / 2), half});
        return Cell{big.chunk, big.layer, big.x, big.y, half};
    }
    static GLuint new_chunk() {
        GLuint t = 0;
        glGenTextures(1, &t);
        glBindTexture(GL_TEXTURE_2D_ARRAY, t);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA8, GLsizei(kPageSide), GLsizei(kPageSide), GLsizei(kChunkLayers), 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        return t;
    }
    // The slot's cell at `side` (rounded up to a power of two from 16 to 256).
    const Cell& cell_for(uint32_t slot, uint32_t side) {
        if (slot >= cells.size()) cells.resize(slot + 1);
        Cell& c = cells[slot];
        const uint32_t level = level_of(side);
        if (c.side != (kMinCell << level)) {
            if (c.side) free_cells[level_of(c.side)].push_back(c);
            c = take_cell(level);
        }
        return c;
    }
    void draw_meshes(const MeshProgram& p, const float vp[16], const std::vector<Draw>& draws, int32_t capture, Shading shading) {
        glUseProgram(p.program);
        glUniformMatrix4fv(p.u_vp, 1, GL_FALSE, vp);
        glBindVertexArray(vao);
        if (shading == Shading::textured) {
            glUniform1i(u_textured_image, 0);
            glActiveTexture(GL_TEXTURE0);
        }
        for (const Draw& d : draws) {
            if (d.capture != capture || d.shading != shading) continue;
            if (shading == Shading::textured) {
                if (d.image >= images.size()) continue;
                glBindTexture(GL_TEXTURE_2D, images[d.image]);
            }
            glBindBuffer(GL_ARRAY_BUFFER, meshes[d.mesh].vbo);
            glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 32, nullptr);
            glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 32, reinterpret_cast<void*>(12));
            glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, 32, reinterpret_cast<void*>(24));
            glEnableVertexAttribArray(0);
            glEnableVertexAttribArray(1);
            glEnableVertexAttribArray(2);
            glUniformMatrix4fv(p.u_model, 1, GL_FALSE, d.model);
            // a mirroring transform (glTF scenes have them) turns counter-clockwise front faces clockwise
            const float* m = d.model;
            const float det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[4] * (m[1] * m[10] - m[2] * m[9]) + m[8] * (m[1] * m[6] - m[2] * m[5]);
            glFrontFace(det < 0 ? GL_CW : GL_CCW);
            glUniform3fv(p.u_color, 1, d.color);
            glDrawElements(GL_TRIANGLES, GLsizei(d.index_count), GL_UNSIGNED_INT, reinterpret_cast<void*>(d.first * sizeof(uint32_t)));
        }
    }
    // After a capture into `cell`: a meshed one's depth read back into the slot's depth mesh; a
    // simple one leaves the slot none.
    void keep_depth_mesh(const Capture& cap, const Cell& cell) {
        if (cap.texture >= depth_meshes.size()) depth_meshes.resize(cap.texture + 1);
        DepthMesh& mesh = depth_meshes[cap.texture];
        mesh.grid = cap.grid;
        if (!cap.grid) return;
        depth_texels.resize(size_t(cell.side) * cell.side);
        glReadPixels(GLint(cell.x), GLint(cell.y), GLsizei(cell.side), GLsizei(cell.side), GL_DEPTH_COMPONENT, GL_FLOAT, depth_texels.data());
        mesh.positions.resize(size_t(cap.grid + 1) * (cap.grid + 1) * 3);
        tcr::depth_mesh(cap.view, cap.projection, depth_texels.data(), cell.side, cap.grid, mesh.positions.data());
    }
    // The frame's meshed imposters, one indexed draw per chunk of the array textures.
    void draw_meshed_imposters(const float vp[16], const std::vector<Draw>& draws) {
        glUseProgram(meshed_program);
        glUniformMatrix4fv(u_meshed_vp, 1, GL_FALSE, vp);
        glUniform1i(u_meshed_image, 0);
        glActiveTexture(GL_TEXTURE0);
        glBindVertexArray(meshed_vao);
        glDisable(GL_CULL_FACE);
        const float page = float(kPageSide);
        for (uint32_t chunk = 0; chunk < chunks.size(); ++chunk) {
            meshed_vertex_data.clear();
            meshed_index_data.clear();
            for (const Draw& d : draws) {
                if (d.shading != Shading::meshed || d.texture >= cells.size() || d.texture >= depth_meshes.size()) continue;
                const Cell& c = cells[d.texture];
                const DepthMesh& mesh = depth_meshes[d.texture];
                if (!c.side || c.chunk != chunk || !mesh.grid) continue;
                const uint32_t g = mesh.grid, base = uint32_t(meshed_vertex_data.size() / kMeshedFloats);
                const float rest[9] = {float(c.x) / page, float(c.y) / page, float(c.side) / page, 0.5f / page, d.color[0], d.color[1], d.color[2], d.tint, float(c.layer)};
                for (uint32_t j = 0; j <= g; ++j)
                    for (uint32_t i = 0; i <= g; ++i) {
                        const float* p = mesh.positions.data() + 3 * (size_t(j) * (g + 1) + i);
                        const float uv[2] = {float(i) / float(g), float(j) / float(g)};
                        meshed_vertex_data.insert(meshed_vertex_data.end(), p, p + 3);
                        meshed_vertex_data.insert(meshed_vertex_data.end(), uv, uv + 2);
                        meshed_vertex_data.insert(meshed_vertex_data.end(), rest, rest + 9);
                    }
                for (uint32_t j = 0; j < g; ++j)
                    for (uint32_t i = 0; i < g; ++i) {
                        const uint32_t a = base + j * (g + 1) + i, b = a + 1, e = a + g + 1, f = e + 1;
                        const uint32_t quad[6] = {a, b, f, a, f, e};
                        meshed_index_data.insert(meshed_index_data.end(), quad, quad + 6);
                    }
            }
            if (meshed_index_data.empty()) continue;
            glBindTexture(GL_TEXTURE_2D_ARRAY, chunks[chunk]);
            glBindBuffer(GL_ARRAY_BUFFER, meshed_vertices);
            glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(meshed_vertex_data.size() * sizeof(float)), meshed_vertex_data.data(), GL_STREAM_DRAW);
            glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(meshed_index_data.size() * sizeof(uint32_t)), meshed_index_data.data(), GL_STREAM_DRAW);
            glDrawElements(GL_TRIANGLES, GLsizei(meshed_index_data.size()), GL_UNSIGNED_INT, nullptr);
        }
        glEnable(GL_CULL_FACE);
        glBindVertexArray(vao);
    }
    void draw_imposters(const float vp[16], const std::vector<Draw>& draws) {
        glUseProgram(imposter_program);
        glUniformMatrix4fv(u_imposter_vp, 1, GL_FALSE, vp);
        glUniform1i(u_image, 0);
        glActiveTexture(GL_TEXTURE0);
        glBindVertexArray(quad_vao);
        glDisable(GL_CULL_FACE);  // seen from behind its capture, a quad still shows (its error is the distortion's)
        for (uint32_t chunk = 0; chunk < chunks.size(); ++chunk) {  // one draw a chunk
            instances.clear();
            for (const Draw& d : draws) {
                if (d.shading != Shading::imposter || d.texture >= cells.size() || !cells[d.texture].side || cells[d.texture].chunk != chunk) continue;
                const Cell& c = cells[d.texture];
                const float page = float(kPageSide);
                instances.insert(instances.end(), d.corners, d.corners + 12);
                const float rest[9] = {float(c.x) / page, float(c.y) / page, float(c.side) / page, 0.5f / page, d.color[0], d.color[1], d.color[2], d.tint, float(c.layer)};
                instances.insert(instances.end(), rest, rest + 9);
            }
            if (instances.empty()) continue;
            glBindTexture(GL_TEXTURE_2D_ARRAY, chunks[chunk]);
            glBindBuffer(GL_ARRAY_BUFFER, quad_instances);
            glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(instances.size() * sizeof(float)), instances.data(), GL_STREAM_DRAW);
            glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(instances.size() / kInstanceFloats));
        }
        glEnable(GL_CULL_FACE);
        glBindVertexArray(vao);
    }
};

Renderer::Renderer(uint32_t width, uint32_t height) : impl_(std::make_unique<Impl>()), width_(width), height_(height) {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    impl_->context = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!impl_->context) throw std::runtime_error("OSMesa: cannot create an OpenGL 3.3 core context");
    impl_->color.resize(size_t(width) * height * 4);
    if (!OSMesaMakeCurrent(impl_->context, impl_->color.data(), GL_UNSIGNED_BYTE, GLsizei(width), GLsizei(height)))
        throw std::runtime_error("OSMesa: cannot make the context current");
    impl_->smooth = impl_->make_mesh_program({"SHADE"});
    impl_->flat = impl_->make_mesh_program({"SHADE flat"});
    impl_->textured = impl_->make_mesh_program({"SHADE", "TEXTURED"});
    impl_->u_textured_image = glGetUniformLocation(impl_->textured.program, "image");
    impl_->imposter_program = link(with_defines(kImposterVertex, {}), with_defines(kImposterFragment, {}));
    impl_->u_imposter_vp = glGetUniformLocation(impl_->imposter_program, "view_projection");
    impl_->u_image = glGetUniformLocation(impl_->imposter_program, "image");
    glGenVertexArrays(1, &impl_->quad_vao);
    glBindVertexArray(impl_->quad_vao);
    glGenBuffers(1, &impl_->quad_instances);
    glBindBuffer(GL_ARRAY_BUFFER, impl_->quad_instances);
    const GLsizei stride = GLsizei(Impl::kInstanceFloats * sizeof(float));
    const int sizes[7] = {3, 3, 3, 3, 4, 4, 1};
    size_t offset = 0;
    for (GLuint a = 0; a < 7; ++a) {
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(offset * sizeof(float)));
        glVertexAttribDivisor(a, 1);
        offset += size_t(sizes[a]);
    }
    impl_->meshed_program = link(with_defines(kImposterVertex, {"MESHED"}), with_defines(kImposterFragment, {}));
    impl_->u_meshed_vp = glGetUniformLocation(impl_->meshed_program, "view_projection");
    impl_->u_meshed_image = glGetUniformLocation(impl_->meshed_program, "image");
    glGenVertexArrays(1, &impl_->meshed_vao);
    glBindVertexArray(impl_->meshed_vao);
    glGenBuffers(1, &impl_->meshed_vertices);
    glGenBuffers(1, &impl_->meshed_indices);
    glBindBuffer(GL_ARRAY_BUFFER, impl_->meshed_vertices);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->meshed_indices);  // the VAO's own index buffer
    {
        const GLsizei meshed_stride = GLsizei(Impl::kMeshedFloats * sizeof(float));
        const int meshed_sizes[5] = {3, 2, 4, 4, 1};
        size_t at = 0;
        for (GLuint a = 0; a < 5; ++a) {
            glEnableVertexAttribArray(a);
            glVertexAttribPointer(a, meshed_sizes[a], GL_FLOAT, GL_FALSE, meshed_stride, reinterpret_cast<const void*>(at * sizeof(float)));
            at += size_t(meshed_sizes[a]);
        }
    }
    glGenFramebuffers(1, &impl_->framebuffer);
    glGenRenderbuffers(1, &impl_->depth);
    glBindRenderbuffer(GL_RENDERBUFFER, impl_->depth);  // a page's depth: every cell renders in its own square of it
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, GLsizei(Impl::kPageSide), GLsizei(Impl::kPageSide));
    glGenVertexArrays(1, &impl_->vao);
    glBindVertexArray(impl_->vao);
    glGenBuffers(1, &impl_->index_buffer);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->index_buffer);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
    glViewport(0, 0, GLsizei(width), GLsizei(height));
}

Renderer::~Renderer() {
    if (impl_ && impl_->context) OSMesaDestroyContext(impl_->context);
}

std::string Renderer::description() const {
    return std::string(reinterpret_cast<const char*>(glGetString(GL_RENDERER))) + ", OpenGL " + reinterpret_cast<const char*>(glGetString(GL_VERSION));
}

uint32_t Renderer::add_mesh(const tom::MeshView& mesh) {
    // interleaved position, normal, texture coordinates, the full vertex array once: any level is
    // a prefix of it
    std::vector<float> data(size_t(mesh.vertex_count) * 8, 0.0f);
    for (uint32_t v = 0; v < mesh.vertex_count; ++v) {
        float* out = data.data() + 8 * size_t(v);
        for (int k = 0; k < 3; ++k) {
            out[k] = mesh.positions[3 * size_t(v) + k];
            out[3 + k] = mesh.normals ? mesh.normals[3 * size_t(v) + k] : 0.0f;
        }
        if (mesh.texcoords) out[6] = mesh.texcoords[2 * size_t(v)], out[7] = mesh.texcoords[2 * size_t(v) + 1];
    }
    Impl::Mesh m;
    glGenBuffers(1, &m.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_STATIC_DRAW);
    impl_->meshes.push_back(m);
    return uint32_t(impl_->meshes.size() - 1);
}

uint32_t Renderer::add_image(uint32_t width, uint32_t height, const unsigned char* rgba) {
    GLuint t = 0;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, GLsizei(width), GLsizei(height), 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    impl_->images.push_back(t);
    return uint32_t(impl_->images.size() - 1);
}

uint32_t Renderer::add_image(const std::string& path) {
    int w = 0, h = 0, channels = 0;
    // rows uploaded top row first: texture coordinate v = 0 is the image's top row, as in glTF
    // and the .tom (OBJ's and PLY's v are flipped on import)
    stbi_set_flip_vertically_on_load(0);
    unsigned char* pixels = stbi_load(path.c_str(), &w, &h, &channels, 4);
    if (!pixels) throw std::runtime_error("cannot read image '" + path + "': " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown reason"));
    const uint32_t handle = add_image(uint32_t(w), uint32_t(h), pixels);
    stbi_image_free(pixels);
    return handle;
}

uint32_t Renderer::add_image(const uint8_t* encoded, size_t bytes, const std::string& name) {
    int w = 0, h = 0, channels = 0;
    stbi_set_flip_vertically_on_load(0);  // as add_image(path)
    if (bytes > size_t(INT32_MAX)) throw std::runtime_error("cannot read image " + name + ": " + std::to_string(bytes) + " bytes");
    unsigned char* pixels = stbi_load_from_memory(encoded, int(bytes), &w, &h, &channels, 4);
    if (!pixels) throw std::runtime_error("cannot read image " + name + ": " + (stbi_failure_reason() ? stbi_failure_reason() : "unknown reason"));
    const uint32_t handle = add_image(uint32_t(w), uint32_t(h), pixels);
    stbi_image_free(pixels);
    return handle;
}

void Renderer::render(const float view[16], const float projection[16], const std::vector<Draw>& draws, const std::vector<uint32_t>& indices,
                      size_t index_count, const std::vector<Capture>& captures) {
    Impl& g = *impl_;
    // the frame's index buffers, streamed into one buffer object (orphaned each frame)
    glBindVertexArray(g.vao);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.index_buffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(index_count * sizeof(uint32_t)), indices.data(), GL_STREAM_DRAW);
    float vp[16];
    for (size_t c = 0; c < captures.size(); ++c) {
        const Capture& cap = captures[c];
        const Impl::Cell cell = g.cell_for(cap.texture, cap.side);
        glBindFramebuffer(GL_FRAMEBUFFER, g.framebuffer);
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, g.chunks[cell.chunk], 0, GLint(cell.layer));
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, g.depth);
        glViewport(GLint(cell.x), GLint(cell.y), GLsizei(cell.side), GLsizei(cell.side));
        glScissor(GLint(cell.x), GLint(cell.y), GLsizei(cell.side), GLsizei(cell.side));
        glEnable(GL_SCISSOR_TEST);  // the clear stays in the cell
        // the background's colour with no coverage: the quad's filtered edge fades into it, not into black
        glClearColor(kBackground[0], kBackground[1], kBackground[2], 0.0f);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glDisable(GL_SCISSOR_TEST);
        tcr::multiply(cap.projection, cap.view, vp);
        g.draw_meshes(g.smooth, vp, draws, int32_t(c), Shading::smooth);
        g.draw_meshes(g.flat, vp, draws, int32_t(c), Shading::flat);
        g.draw_meshes(g.textured, vp, draws, int32_t(c), Shading::textured);
        g.keep_depth_mesh(cap, cell);
    }
    // The captures finished before the frame: left to llvmpipe's queue, they make the *next*
    // frame's draws stall now and then (frames of 1.5 to 3 times the budget right after frames
    // with captures, in whichever selector draws next). The wait is in the frame's time, as the
    // refresh's cost.
    if (!captures.empty()) glFinish();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, GLsizei(width_), GLsizei(height_));
    glClearColor(kBackground[0], kBackground[1], kBackground[2], 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    tcr::multiply(projection, view, vp);
    g.draw_meshes(g.smooth, vp, draws, -1, Shading::smooth);
    g.draw_meshes(g.flat, vp, draws, -1, Shading::flat);
    g.draw_meshes(g.textured, vp, draws, -1, Shading::textured);
    g.draw_imposters(vp, draws);
    g.draw_meshed_imposters(vp, draws);
    glFinish();
}

size_t Renderer::texture_bytes() const noexcept {
    return impl_->chunks.size() * Impl::kChunkLayers * Impl::kPageSide * Impl::kPageSide * 4;
}

std::vector<unsigned char> Renderer::read_pixels() const {
    std::vector<unsigned char> pixels(size_t(width_) * height_ * 4);
    glReadPixels(0, 0, GLsizei(width_), GLsizei(height_), GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    return pixels;
}

bool Renderer::save_png(const std::string& path) {
    const std::vector<unsigned char> pixels = read_pixels();
    // OpenGL's rows start at the bottom
    std::vector<unsigned char> flipped(pixels.size());
    for (uint32_t y = 0; y < height_; ++y)
        std::copy(pixels.begin() + ptrdiff_t(size_t(height_ - 1 - y) * width_ * 4), pixels.begin() + ptrdiff_t(size_t(height_ - y) * width_ * 4),
                  flipped.begin() + ptrdiff_t(size_t(y) * width_ * 4));
    return stbi_write_png(path.c_str(), int(width_), int(height_), 4, flipped.data(), int(width_ * 4)) != 0;
}

} // namespace walk
