#include "tool_common.h"

#include <algorithm>
#include <filesystem>
#include <map>

#include <unistd.h>

#include "tom/import.h"

namespace fs = std::filesystem;

namespace tools {

int parse(CLI::App& app, int argc, char** argv) {
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return exit_usage;
    }
    return -1;
}

std::vector<Job> plan_jobs(const std::vector<std::string>& inputs, const std::string& outdir, const std::string& suffix,
                           std::vector<std::string>& errors) {
    struct Found {
        fs::path file, relative_dir;
    };
    std::vector<Found> found;
    for (const std::string& in : inputs) {
        std::error_code ec;
        const fs::path p(in);
        if (fs::is_directory(p, ec)) {
            std::vector<fs::path> files;
            for (auto it = fs::recursive_directory_iterator(p, fs::directory_options::skip_permission_denied, ec);
                 !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
                if (it->is_regular_file(ec) && tom::is_importable(it->path().string())) files.push_back(it->path());
            if (ec) errors.push_back(in + ": cannot list folder: " + ec.message());
            std::sort(files.begin(), files.end());
            for (const fs::path& f : files) found.push_back({f, f.parent_path().lexically_relative(p)});
        } else if (fs::exists(p, ec)) {
            found.push_back({p, fs::path()});
        } else {
            errors.push_back(in + ": no such file or folder");
        }
    }
    // drop repeated inputs, keep the first
    std::vector<Found> unique;
    std::map<std::string, bool> seen;
    for (const Found& f : found) {
        std::error_code ec;
        const std::string key = fs::weakly_canonical(f.file, ec).string();
        if (!seen[key]) {
            seen[key] = true;
            unique.push_back(f);
        }
    }
    auto out_name = [&](const Found& f, bool keep_ext) {
        std::string name = keep_ext ? f.file.filename().string() : f.file.stem().string();
        return (fs::path(outdir) / f.relative_dir / (name + suffix)).lexically_normal().string();
    };
    std::map<std::string, int> uses;
    for (const Found& f : unique) ++uses[out_name(f, false)];
    std::vector<Job> jobs;
    for (const Found& f : unique) jobs.push_back({f.file.string(), out_name(f, uses[out_name(f, false)] > 1)});
    return jobs;
}

std::string human_bytes(uint64_t bytes) {
    char buf[64];
    if (bytes < 10 * 1024)
        std::snprintf(buf, sizeof buf, "%llu B", static_cast<unsigned long long>(bytes));
    else if (bytes < 10ull * 1024 * 1024)
        std::snprintf(buf, sizeof buf, "%.1f KiB", double(bytes) / 1024.0);
    else
        std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
    return buf;
}

bool is_terminal(int fd) { return ::isatty(fd) != 0; }

} // namespace tools
