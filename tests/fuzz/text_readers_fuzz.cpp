// The text readers of libtcr and the walkthrough on hostile bytes (TOM_FUZZ_CALIBRATION: the
// calibration file; otherwise the walkthrough's scene file): an error naming the file and the
// line, never a crash.

#include <cstdint>

#include "fuzz_support.h"
#include "tom/errors.h"
#ifdef TOM_FUZZ_CALIBRATION
#include "tcr/model.h"
#else
#include "scene.h"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = fuzz::as_file(data, size, "txt");
    try {
#ifdef TOM_FUZZ_CALIBRATION
        const tcr::CostModel m = tcr::read_cost_model(path);
        if (!(m.t_tri_ms >= 0) || !(m.safety_ms >= 0)) __builtin_trap();  // the reader promises non-negative coefficients
#else
        const walk::Scene s = walk::read_scene(path);
        for (const walk::Instance& i : s.instances)
            if (i.mesh >= s.meshes.size()) __builtin_trap();
#endif
    } catch (const tom::Error&) {
    }
    return 0;
}
