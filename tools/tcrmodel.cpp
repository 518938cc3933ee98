// tcrmodel: Pasman & Jansen's model of polygons against imposters (tcr/imposters.h) for one
// object over distance: the polygons each representation needs, its bytes, texture, link and
// render load, which meets the distortion bound at least cost, and where the choice switches.

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tcr/imposters.h"
#include "tom/stream/stream_file.h"
#include "tom/error_curve.h"
#include "tom/errors.h"
#include "tom/format.h"
#include "tool_common.h"

namespace im = tcr::imposters;

namespace {

struct Options {
    bool paper = false, json = false;
    std::string tom_file, csv;
    double scale = 1.0;              // metres per object unit (--tom)
    double pixels = 0, width = 640, fov_degrees = 40;
    std::vector<double> distances = {0.5, 1, 2, 5, 10, 15, 20, 30, 50, 100, 200};
    double max_distance = 1000;
};

// The paper's reading of its Figure 11 (section 6.1), beside which --paper-example prints the model's.
struct PaperFigures {
    double polygons_below = 15, simple_imposters_above = 50, full_resolution_below = 1;
};

nlohmann::ordered_json number(double x) { return std::isfinite(x) ? nlohmann::ordered_json(x) : nlohmann::ordered_json(); }

nlohmann::ordered_json choice_json(const im::Choice& c) {
    return {{"method", im::to_string(c.method)},           {"feasible", c.feasible},
            {"distortion_rad", number(c.distortion)},      {"polygons", number(c.polygons)},
            {"geometry_bytes", number(c.geometry_bytes)},  {"texture_bytes", number(c.texture_bytes)},
            {"link_bytes_per_s", number(c.link_bytes_per_s)}, {"refreshes_per_s", c.refreshes_per_s},
            {"screen_pixels", c.screen_pixels}};
}

// k, the full model's triangles and the radius from a .tom file's first mesh with a stored curve.
void read_mesh(const Options& opt, im::Setting& s) {
    const tom::File file = tom::open_any(opt.tom_file);
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const tom::MeshView& m = file.mesh(i);
        const std::optional<tom::ErrorCurve> curve = tom::read_error_curve(m);
        if (!curve) continue;
        s.k = curve->k_mean;
        s.max_polygons = m.triangle_count;
        double d2 = 0;
        for (int a = 0; a < 3; ++a) d2 += double(m.bounds_max[a] - m.bounds_min[a]) * double(m.bounds_max[a] - m.bounds_min[a]);
        s.radius = 0.5 * std::sqrt(d2) * opt.scale;
        return;
    }
    throw tom::ArgumentError(opt.tom_file + ": no mesh has a stored error curve (convert it without --no-error-curve)");
}

void print_table(const im::Setting& s, const Options& opt) {
    std::printf("Pasman & Jansen: r %.3g m, k %.3g, D %.3g mrad, v %.3g m/s, lifetime %.3g s, MinDist %.3g m%s\n", s.radius, s.k, 1e3 * s.distortion, s.speed,
                s.lifetime, s.min_distance, s.max_polygons > 0 ? (", at most " + std::to_string(int64_t(s.max_polygons)) + " polygons").c_str() : "");
    std::printf("link load in kB/s (- : the bound cannot be met); geometry 25 bits a polygon, textures JPEG 20:1 or MPEG 75:1\n");
    std::printf("%8s %7s %9s | %9s %9s %9s %9s %9s %9s %9s | %s\n", "d m", "theta", "polygons", "polygons", "increm.", "vpt-dep", "meshed", "simple", "IwD", "LDI",
                "cheapest");
    for (double d : opt.distances) {
        const std::vector<im::Choice> all = im::evaluate(s, d);
        const double theta = im::reachable_angle(d, s.radius, s.speed * s.lifetime, s.min_distance);
        std::printf("%8.3g %6.2f° %9.0f |", d, theta * 180.0 / 3.14159265358979323846, all[0].polygons);
        for (const im::Choice& c : all) {
            if (c.feasible)
                std::printf(" %9.3g", c.link_bytes_per_s / 1e3);
            else
                std::printf(" %9s", "-");
        }
        std::printf(" | %s\n", im::to_string(im::cheapest(s, d).method));
    }
}

void write_csv(const im::Setting& s, const Options& opt) {
    std::ofstream out(opt.csv);
    out << "distance_m,method,feasible,polygons,link_bytes_per_s,texture_bytes,distortion_rad\n";
    for (int i = 0; i <= 240; ++i) {
        const double d = s.min_distance * std::pow(opt.max_distance / s.min_distance, i / 240.0);
        for (const im::Choice& c : im::evaluate(s, d))
            out << d << ',' << im::to_string(c.method) << ',' << (c.feasible ? 1 : 0) << ',' << c.polygons << ',' << c.link_bytes_per_s << ','
                << c.texture_bytes << ',' << c.distortion << '\n';
    }
    if (!out) throw tom::IoError("cannot write '" + opt.csv + "'");
}

} // namespace

int main(int argc, char** argv) {
    Options opt;
    im::Setting s = im::paper_example();
    CLI::App app{"tcrmodel: Pasman & Jansen's model of simplified polygons against imposters, over distance"};
    app.set_version_flag("--version", "tcrmodel 0.1.0");
    app.add_flag("--paper-example", opt.paper, "The paper's Figure 11 setting (the defaults), compared with its switching distances");
    app.add_option("--tom", opt.tom_file, "Take k (the stored error curve's k_mean), the full model's triangles and the radius from this .tom");
    app.add_option("--scale", opt.scale, "Metres per object unit of --tom (default 1)")->check(CLI::PositiveNumber);
    app.add_option("--radius", s.radius, "Object radius r in metres (default 1)")->check(CLI::PositiveNumber);
    app.add_option("--k", s.k, "The object's D = k / N (default 5)")->check(CLI::PositiveNumber);
    app.add_option("--distortion", s.distortion, "Allowed visual distortion D in radians (default 0.001)")->check(CLI::PositiveNumber);
    app.add_option("--pixels", opt.pixels, "Allowed distortion in pixels instead, with --width and --fov")->check(CLI::PositiveNumber);
    app.add_option("--width", opt.width, "Display width in pixels for --pixels (default 640)")->check(CLI::PositiveNumber);
    app.add_option("--fov", opt.fov_degrees, "Horizontal field of view in degrees for --pixels (default 40)")->check(CLI::Range(1.0, 179.0));
    app.add_option("--speed", s.speed, "Viewer speed v in m/s (default 1)")->check(CLI::NonNegativeNumber);
    app.add_option("--lifetime", s.lifetime, "Seconds a representation must last, T (default 1)")->check(CLI::PositiveNumber);
    app.add_option("--min-distance", s.min_distance, "The nearest the viewer comes, MinDist in metres (default 0.2)")->check(CLI::PositiveNumber);
    app.add_option("--max-polygons", s.max_polygons, "Polygons of the full model (default: as many as needed)")->check(CLI::NonNegativeNumber);
    app.add_option("--distances", opt.distances, "Distances of the table in metres (default 0.5,1,2,5,10,15,20,30,50,100,200)")->delimiter(',');
    app.add_option("--max-distance", opt.max_distance, "Farthest distance scanned for the switching distances (default 1000)")->check(CLI::PositiveNumber);
    app.add_flag("--json", opt.json, "One JSON object: the setting, the switching distances, every method at every distance");
    app.add_option("--csv", opt.csv, "Also write every method on 241 log-spaced distances as CSV (scripts/plot-model.py plots it)");
    app.footer("Exit codes: 0 ok, 1 a file could not be read or written, 2 usage error.\nExample: tcrmodel --paper-example; tcrmodel --tom out/bunny00.tom --scale 10");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    try {
        if (!opt.tom_file.empty()) read_mesh(opt, s);
        if (opt.pixels > 0) s.distortion = opt.pixels * opt.fov_degrees * 3.14159265358979323846 / 180.0 / opt.width;
        const im::Switching w = im::switching_distances(s, opt.max_distance);
        const PaperFigures paper;
        if (!opt.csv.empty()) write_csv(s, opt);
        if (opt.json) {
            nlohmann::ordered_json j;
            j["setting"] = {{"radius_m", s.radius}, {"k", s.k}, {"distortion_rad", s.distortion}, {"speed_m_s", s.speed}, {"lifetime_s", s.lifetime},
                            {"min_distance_m", s.min_distance}, {"max_polygons", s.max_polygons}};
            j["polygons_below_m"] = number(w.polygons_below);
            j["meshed_imposters_above_m"] = number(w.meshed_imposters_above);
            j["simple_imposters_above_m"] = number(w.simple_imposters_above);
            j["full_resolution_below_m"] = number(w.full_resolution_below);
            if (opt.paper)
                j["paper"] = {{"polygons_below_m", paper.polygons_below},
                              {"simple_imposters_above_m", paper.simple_imposters_above},
                              {"full_resolution_below_m", paper.full_resolution_below},
                              {"ratio_polygons_below", w.polygons_below / paper.polygons_below},
                              {"ratio_simple_imposters_above", w.simple_imposters_above / paper.simple_imposters_above},
                              {"ratio_full_resolution_below", w.full_resolution_below / paper.full_resolution_below}};
            j["distances"] = nlohmann::json::array();
            for (double d : opt.distances) {
                nlohmann::ordered_json row;
                row["distance_m"] = d;
                row["theta_rad"] = im::reachable_angle(d, s.radius, s.speed * s.lifetime, s.min_distance);
                row["cheapest"] = im::to_string(im::cheapest(s, d).method);
                row["methods"] = nlohmann::json::array();
                for (const im::Choice& c : im::evaluate(s, d)) row["methods"].push_back(choice_json(c));
                j["distances"].push_back(row);
            }
            std::printf("%s\n", j.dump(2).c_str());
        } else {
            print_table(s, opt);
            std::printf("switching: the full model below %.3g m; polygons below %.3g m (meshed imposters from there); simple imposters from %.3g m\n",
                        w.full_resolution_below, w.polygons_below, w.simple_imposters_above);
            if (opt.paper)
                std::printf("the paper (6.1): full resolution below about %g m, polygons below %g m, simple imposters from %g m: ratios %.2f, %.2f, %.2f\n",
                            paper.full_resolution_below, paper.polygons_below, paper.simple_imposters_above, w.full_resolution_below / paper.full_resolution_below,
                            w.polygons_below / paper.polygons_below, w.simple_imposters_above / paper.simple_imposters_above);
        }
        return tools::exit_ok;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return tools::exit_failed;
    }
}
