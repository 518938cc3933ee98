#pragma once
// The walkthrough's renderer as calibration's (tcr::calibrate): its meshes by their handles,
// imposter slots as textures from 1000 on, and a 256 x 256 checker for the textured draws.

#include <cstdint>
#include <vector>

#include "renderer.h"
#include "tcr/calibrate.h"

namespace walk {

class CalibrationTimer final : public tcr::CalibrationRenderer {
public:
    CalibrationTimer(Renderer& renderer, const std::vector<uint32_t>& handles) : r_(renderer), handles_(handles) {}
    uint32_t width() const override { return r_.width(); }
    uint32_t height() const override { return r_.height(); }
    double time_frame(const tcr::Camera& cam, const std::vector<tcr::CalibrationDraw>& draws, tcr::Representation way) override;
    double time_imposters(const tcr::Camera& cam, const std::vector<tcr::CalibrationCapture>& captures,
                          const std::vector<tcr::CalibrationImposter>& imposters) override;

private:
    void begin_frame();
    Renderer::Draw walk_draw(const tcr::CalibrationDraw& d, Renderer::Shading shading, uint32_t image);
    double render(const tcr::Camera& cam);
    uint32_t checker();

    struct Offset {
        const uint32_t* indices;
        uint32_t count;
        size_t first;
    };
    Renderer& r_;
    const std::vector<uint32_t>& handles_;
    std::vector<Renderer::Draw> draws_;
    std::vector<Renderer::Capture> captures_;
    std::vector<uint32_t> indices_;
    std::vector<Offset> offsets_;
    int64_t checker_ = -1;
};

} // namespace walk
