// OSMesa OpenGL 3.3 core renderer for the walkthrough.

#define GL_GLEXT_PROTOTYPES
#include "renderer.h"

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <stb/stb_image_write.h>

#include <stdexcept>

#include "tcr/view.h"

namespace walk {

namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
uniform mat4 model;
uniform mat4 view_projection;
uniform vec3 color;
out vec3 shade;
void main() {
    vec3 n = normalize(mat3(model) * normal);
    // Gouraud: two directional lights and an ambient term, lit per vertex
    float d = 0.15 + 0.65 * max(dot(n, normalize(vec3(0.4, 0.8, 0.5))), 0.0) + 0.3 * max(dot(n, normalize(vec3(-0.6, 0.2, -0.4))), 0.0);
    shade = color * d;
    gl_Position = view_projection * model * vec4(position, 1.0);
}
)";

const char* kFragment = R"(#version 330 core
in vec3 shade;
out vec4 frag;
void main() { frag = vec4(shade, 1.0); }
)";

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

} // namespace

struct Renderer::Impl {
    OSMesaContext context = nullptr;
    std::vector<unsigned char> color;
    GLuint program = 0, vao = 0, index_buffer = 0;
    GLint u_model = -1, u_vp = -1, u_color = -1;
    struct Mesh {
        GLuint vbo;
    };
    std::vector<Mesh> meshes;
};

Renderer::Renderer(uint32_t width, uint32_t height) : impl_(std::make_unique<Impl>()), width_(width), height_(height) {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    impl_->context = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!impl_->context) throw std::runtime_error("OSMesa: cannot create an OpenGL 3.3 core context");
    impl_->color.resize(size_t(width) * height * 4);
    if (!OSMesaMakeCurrent(impl_->context, impl_->color.data(), GL_UNSIGNED_BYTE, GLsizei(width), GLsizei(height)))
        throw std::runtime_error("OSMesa: cannot make the context current");
    impl_->program = glCreateProgram();
    glAttachShader(impl_->program, compile(GL_VERTEX_SHADER, kVertex));
    glAttachShader(impl_->program, compile(GL_FRAGMENT_SHADER, kFragment));
    glLinkProgram(impl_->program);
    GLint ok = 0;
    glGetProgramiv(impl_->program, GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("OpenGL: cannot link the shaders");
    impl_->u_model = glGetUniformLocation(impl_->program, "model");
    impl_->u_vp = glGetUniformLocation(impl_->program, "view_projection");
    impl_->u_color = glGetUniformLocation(impl_->program, "color");
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
    // interleaved position + normal, the full vertex array once: any level is a prefix of it
    std::vector<float> data(size_t(mesh.vertex_count) * 6);
    for (uint32_t v = 0; v < mesh.vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            data[6 * size_t(v) + k] = mesh.positions[3 * size_t(v) + k];
            data[6 * size_t(v) + 3 + k] = mesh.normals ? mesh.normals[3 * size_t(v) + k] : 0.0f;
        }
    Impl::Mesh m;
    glGenBuffers(1, &m.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_STATIC_DRAW);
    impl_->meshes.push_back(m);
    return uint32_t(impl_->meshes.size() - 1);
}

void Renderer::render(const float view[16], const float projection[16], const std::vector<Draw>& draws, const std::vector<uint32_t>& indices,
                      size_t index_count) {
    glClearColor(0.92f, 0.93f, 0.95f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glUseProgram(impl_->program);
    float vp[16];
    tcr::multiply(projection, view, vp);
    glUniformMatrix4fv(impl_->u_vp, 1, GL_FALSE, vp);
    // the frame's index buffers, streamed into one buffer object (orphaned each frame)
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->index_buffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(index_count * sizeof(uint32_t)), indices.data(), GL_STREAM_DRAW);
    for (const Draw& d : draws) {
        glBindBuffer(GL_ARRAY_BUFFER, impl_->meshes[d.mesh].vbo);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 24, nullptr);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 24, reinterpret_cast<void*>(12));
        glEnableVertexAttribArray(0);
        glEnableVertexAttribArray(1);
        glUniformMatrix4fv(impl_->u_model, 1, GL_FALSE, d.model);
        // a mirroring transform (glTF scenes have them) turns counter-clockwise front faces clockwise
        const float* m = d.model;
        const float det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[4] * (m[1] * m[10] - m[2] * m[9]) + m[8] * (m[1] * m[6] - m[2] * m[5]);
        glFrontFace(det < 0 ? GL_CW : GL_CCW);
        glUniform3fv(impl_->u_color, 1, d.color);
        glDrawElements(GL_TRIANGLES, GLsizei(d.index_count), GL_UNSIGNED_INT, reinterpret_cast<void*>(d.first * sizeof(uint32_t)));
    }
    glFinish();
}

bool Renderer::save_png(const std::string& path) {
    std::vector<unsigned char> pixels(size_t(width_) * height_ * 4);
    glReadPixels(0, 0, GLsizei(width_), GLsizei(height_), GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    // OpenGL's rows start at the bottom
    std::vector<unsigned char> flipped(pixels.size());
    for (uint32_t y = 0; y < height_; ++y)
        std::copy(pixels.begin() + ptrdiff_t(size_t(height_ - 1 - y) * width_ * 4), pixels.begin() + ptrdiff_t(size_t(height_ - y) * width_ * 4),
                  flipped.begin() + ptrdiff_t(size_t(y) * width_ * 4));
    return stbi_write_png(path.c_str(), int(width_), int(height_), 4, flipped.data(), int(width_ * 4)) != 0;
}

} // namespace walk
