// Cost model calibration and its file format.
//
// References: T. Funkhouser, C. Sequin. Adaptive Display Algorithm for Interactive Frame Rates
// During Visualization of Complex Virtual Environments. SIGGRAPH 1993 (cost = max(C1 polys +
// C2 verts, C3 pixels), fitted from sample renderings); E. Gobbetti, E. Bouvier. Time-critical
// multiresolution scene rendering. IEEE Visualization 1999 (t_setup, t_tri, t_pix, safety).

#include "tom/errors.h"
#include "tcr/model.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tcr {

namespace {

// Solves the normal equations of min |A x - b| over the columns flagged in `use`, by Gaussian
// elimination with partial pivoting; unused or negative coefficients are dropped and the
// problem re-solved (a small active-set loop for x >= 0).
std::vector<double> nonnegative_least_squares(const std::vector<std::vector<double>>& rows, const std::vector<double>& b, size_t cols) {
    std::vector<bool> use(cols, true);
    std::vector<double> x(cols, 0.0);
    for (size_t iter = 0; iter < cols + 1; ++iter) {
        std::vector<size_t> idx;
        for (size_t c = 0; c < cols; ++c)
            if (use[c]) idx.push_back(c);
        const size_t k = idx.size();
        if (k == 0) break;
        std::vector<std::vector<double>> m(k, std::vector<double>(k + 1, 0.0));
        for (size_t r = 0; r < rows.size(); ++r)
            for (size_t i = 0; i < k; ++i) {
                for (size_t j = 0; j < k; ++j) m[i][j] += rows[r][idx[i]] * rows[r][idx[j]];
                m[i][k] += rows[r][idx[i]] * b[r];
            }
        for (size_t i = 0; i < k; ++i) m[i][i] += 1e-18;  // keeps an all-zero column solvable
        for (size_t col = 0; col < k; ++col) {
            size_t piv = col;
            for (size_t r = col + 1; r < k; ++r)
                if (std::fabs(m[r][col]) > std::fabs(m[piv][col])) piv = r;
            std::swap(m[col], m[piv]);
            if (m[col][col] == 0.0) continue;
            for (size_t r = 0; r < k; ++r) {
                if (r == col) continue;
                const double f = m[r][col] / m[col][col];
                for (size_t c = col; c <= k; ++c) m[r][c] -= f * m[col][c];
            }
        }
        std::fill(x.begin(), x.end(), 0.0);
        bool negative = false;
        for (size_t i = 0; i < k; ++i) {
            x[idx[i]] = m[i][i] != 0.0 ? m[i][k] / m[i][i] : 0.0;
            if (x[idx[i]] < 0) negative = true;
        }
        if (!negative) break;
        // drop the most negative coefficient and solve again
        size_t worst = idx[0];
        for (size_t i : idx)
            if (x[i] < x[worst]) worst = i;
        use[worst] = false;
    }
    for (double& v : x) v = std::max(0.0, v);
    return x;
}

} // namespace

CalibrationResult fit_cost_model(const std::vector<CostSample>& samples) {
    CalibrationResult r;
    if (samples.empty()) return r;
    // start: every sample geometry bound
    std::vector<char> fill(samples.size(), 0);
    CostModel model;
    // relative errors: each sample's row divided by its time, so objects of a few hundred
    // triangles count as much as those of tens of thousands (absolute residuals let the largest
    // samples decide and leave the small ones far off); times below a
    // thousandth of the largest are weighted as that
    double longest = 0;
    for (const CostSample& s : samples) longest = std::max(longest, s.time_ms);
    const double floor_ms = std::max(1e-9, 1e-3 * longest);
    for (int round = 0; round < 50; ++round) {
        // unknowns: setup, tri, vert, pix
        std::vector<std::vector<double>> rows;
        std::vector<double> b;
        for (size_t i = 0; i < samples.size(); ++i) {
            const CostSample& s = samples[i];
            const double w = 1.0 / std::max(s.time_ms, floor_ms);
            if (fill[i])
                rows.push_back({w, 0.0, 0.0, w * s.pixels});
            else
                rows.push_back({w, w * s.triangles, w * s.vertices, 0.0});
            b.push_back(w * s.time_ms);
        }
        // scale columns so the solve is well conditioned
        double scale[4] = {1, 1, 1, 1};
        for (size_t c = 1; c < 4; ++c) {
            double mx = 0;
            for (auto& row : rows) mx = std::max(mx, std::fabs(row[c]));
            scale[c] = mx > 0 ? mx : 1;
            for (auto& row : rows) row[c] /= scale[c];
        }
        std::vector<double> x = nonnegative_least_squares(rows, b, 4);
        model.t_setup_ms = x[0];
        model.t_tri_ms = x[1] / scale[1];
        model.t_vert_ms = x[2] / scale[2];
        model.t_pix_ms = x[3] / scale[3];
        bool changed = false;
        for (size_t i = 0; i < samples.size(); ++i) {
            const double geometry = model.t_tri_ms * samples[i].triangles + model.t_vert_ms * samples[i].vertices;
            const double pix = model.t_pix_ms * samples[i].pixels;
            const char f = pix > geometry ? 1 : 0;
            if (f != fill[i]) changed = true;
            fill[i] = f;
        }
        // keep at least one sample on each side so both halves of the model are fitted
        size_t fills = 0;
        for (char f : fill) fills += size_t(f);
        if (round == 0 && fills == 0) {
            // no sample classed as fill bound yet: seed with the highest pixels-per-triangle ones
            size_t best = 0;
            for (size_t i = 1; i < samples.size(); ++i)
                if (samples[i].pixels / (samples[i].triangles + 1) > samples[best].pixels / (samples[best].triangles + 1)) best = i;
            fill[best] = 1;
            changed = true;
        }
        if (!changed) break;
    }
    double sq = 0, rel = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
        const double p = model.object_ms(samples[i].triangles, samples[i].vertices, samples[i].pixels);
        const double d = p - samples[i].time_ms;
        sq += d * d;
        if (samples[i].time_ms > 0) rel += std::fabs(d) / samples[i].time_ms;
        (fill[i] ? r.fill_bound : r.geometry_bound)++;
    }
    r.model = model;
    r.rms_error_ms = std::sqrt(sq / double(samples.size()));
    r.mean_relative_error = rel / double(samples.size());
    return r;
}

namespace {

// The calibration file's keys, in the order they are written (docs/CALIBRATION.md).
struct Key {
    const char* name;
    double CostModel::*field;
};
constexpr Key kKeys[] = {
    {"t_init_ms", &CostModel::t_init_ms},
    {"t_final_ms", &CostModel::t_final_ms},
    {"t_setup_ms", &CostModel::t_setup_ms},
    {"t_tri_ms", &CostModel::t_tri_ms},
    {"t_vert_ms", &CostModel::t_vert_ms},
    {"t_pix_ms", &CostModel::t_pix_ms},
    {"safety_ms", &CostModel::safety_ms},
    {"noise_rel", &CostModel::noise_rel},
    {"flat_t_tri_ms", &CostModel::flat_t_tri_ms},
    {"flat_t_vert_ms", &CostModel::flat_t_vert_ms},
    {"flat_t_pix_ms", &CostModel::flat_t_pix_ms},
    {"textured_t_tri_ms", &CostModel::textured_t_tri_ms},
    {"textured_t_vert_ms", &CostModel::textured_t_vert_ms},
    {"textured_t_pix_ms", &CostModel::textured_t_pix_ms},
    {"imposter_t_setup_ms", &CostModel::imposter_t_setup_ms},
    {"imposter_t_pix_ms", &CostModel::imposter_t_pix_ms},
    {"refresh_t_setup_ms", &CostModel::refresh_t_setup_ms},
    {"meshed_t_tri_ms", &CostModel::meshed_t_tri_ms},
    {"meshed_refresh_t_setup_ms", &CostModel::meshed_refresh_t_setup_ms},
};

} // namespace

CostModel read_cost_model(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw tom::IoError("cannot open calibration file '" + path + "'");
    CostModel m;
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        const size_t hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::istringstream ls(line);
        std::string key;
        if (!(ls >> key)) continue;
        double value;
        std::string rest;
        if (!(ls >> value) || (ls >> rest) || !std::isfinite(value) || value < 0)
            throw tom::ParseError(path + ":" + std::to_string(number) + ": expected '" + key + " <non-negative number>'");
        const Key* known = std::find_if(std::begin(kKeys), std::end(kKeys), [&](const Key& k) { return key == k.name; });
        if (known == std::end(kKeys)) throw tom::ParseError(path + ":" + std::to_string(number) + ": unknown key '" + key + "'");
        m.*(known->field) = value;
    }
    return m;
}

void write_cost_model(const std::string& path, const CostModel& m, const std::string& comment) {
    std::ofstream out(path);
    if (!out) throw tom::IoError("cannot write calibration file '" + path + "'");
    out << "# libtcr cost model (docs/CALIBRATION.md); times in milliseconds\n";
    if (!comment.empty()) out << "# " << comment << "\n";
    out.precision(9);
    for (const Key& k : kKeys) out << k.name << ' ' << m.*(k.field) << '\n';
    if (!out) throw tom::IoError("cannot write calibration file '" + path + "'");
}

} // namespace tcr
