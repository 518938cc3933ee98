// The walkthrough's renderer as calibration's (calibration_timer.h).

#include "calibration_timer.h"

#include <algorithm>

#include "world.h"

namespace walk {

double CalibrationTimer::time_frame(const tcr::Camera& cam, const std::vector<tcr::CalibrationDraw>& draws, tcr::Representation way) {
    using S = Renderer::Shading;
    const S shading = way == tcr::Representation::flat ? S::flat : way == tcr::Representation::textured ? S::textured : S::smooth;
    if (way != tcr::Representation::smooth && shading == S::smooth) return -1;
    begin_frame();
    const uint32_t image = shading == S::textured ? checker() : 0;
    for (const tcr::CalibrationDraw& d : draws) draws_.push_back(walk_draw(d, shading, image));
    return render(cam);
}

double CalibrationTimer::time_imposters(const tcr::Camera& cam, const std::vector<tcr::CalibrationCapture>& captures,
                                        const std::vector<tcr::CalibrationImposter>& imposters) {
    begin_frame();
    for (const tcr::CalibrationCapture& c : captures) {
        Renderer::Capture cap{1000 + c.slot, c.side, {}, {}, c.grid};
        std::copy(c.view, c.view + 16, cap.view);
        std::copy(c.projection, c.projection + 16, cap.projection);
        draws_.push_back(walk_draw(c.draw, Renderer::Shading::smooth, 0));
        draws_.back().capture = int32_t(captures_.size());
        captures_.push_back(cap);
    }
    for (const tcr::CalibrationImposter& q : imposters) {
        Renderer::Draw d{0, nullptr, 0, 0, {kGrey[0], kGrey[1], kGrey[2]}};
        d.shading = q.meshed ? Renderer::Shading::meshed : Renderer::Shading::imposter;
        d.texture = 1000 + q.slot;
        std::copy(q.corners, q.corners + 12, d.corners);
        draws_.push_back(d);
    }
    return render(cam);
}

void CalibrationTimer::begin_frame() { draws_.clear(), captures_.clear(), indices_.clear(), offsets_.clear(); }

// where the draw's indices sit in the frame's index array (each distinct level once)
Renderer::Draw CalibrationTimer::walk_draw(const tcr::CalibrationDraw& d, Renderer::Shading shading, uint32_t image) {
    size_t first = indices_.size();
    const auto known = std::find_if(offsets_.begin(), offsets_.end(), [&](const Offset& o) { return o.indices == d.indices && o.count == d.index_count; });
    if (known != offsets_.end()) {
        first = known->first;
    } else {
        offsets_.push_back({d.indices, d.index_count, first});
        indices_.insert(indices_.end(), d.indices, d.indices + d.index_count);
    }
    Renderer::Draw w{handles_[d.mesh], d.model, first, d.index_count, {kGrey[0], kGrey[1], kGrey[2]}};
    w.shading = shading;
    w.image = image;
    return w;
}

double CalibrationTimer::render(const tcr::Camera& cam) {
    const auto t0 = Clock::now();
    r_.render(cam.view, cam.projection, draws_, indices_, indices_.size(), captures_);
    return ms_since(t0);
}

uint32_t CalibrationTimer::checker() {
    if (checker_ >= 0) return uint32_t(checker_);
    std::vector<unsigned char> rgba(256 * 256 * 4);
    for (size_t i = 0; i < 256 * 256; ++i) {
        const unsigned char v = ((i % 256) / 16 + (i / 256) / 16) % 2 ? 230 : 60;
        rgba[4 * i] = rgba[4 * i + 1] = rgba[4 * i + 2] = v, rgba[4 * i + 3] = 255;
    }
    checker_ = int64_t(r_.add_image(256, 256, rgba.data()));
    return uint32_t(checker_);
}

} // namespace walk
