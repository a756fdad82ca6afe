// SPDX-License-Identifier: Apache-2.0
// The HTML report of a command's results (today `envpis compare`'s): DIR/index.html is
// report/template.html with report/report.css, report/report.js and the results JSON embedded, so it
// opens from the file system with no server; the plots are drawn by report/plots.py (matplotlib) into
// DIR/plots, and their manifest goes into the JSON as "plots".
//
// The report is driven by the JSON alone: a command adds a section by adding its results under a key of
// its own (say "analysis") before add_plots / write_report_html, and report.js (and plots.py, for a
// figure) learn to show that key. Nothing here knows what the results are.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace envpis::app {

/// The directory of template.html, report.css, report.js and plots.py: `option` (--report-dir: throws
/// Error when it has no template.html), $ENVPIS_REPORT_DIR, the source tree this binary was built from,
/// or <prefix>/share/envpis/report next to an installed binary; empty when none has the template.
std::string find_report_dir(const std::string& option);

/// Runs `report_dir`/plots.py on the JSON already written at `json_path` (it writes its figures and
/// plots/manifest.json beside it) and sets j["plots"] to the manifest. When there are no plots (disabled,
/// no report directory, no python3 with matplotlib, the script failed) sets j["plots"] = null and
/// j["plots_unavailable"] to why, and unless `disabled` warns "envpis COMMAND: warning: ..." on stderr.
void add_plots(nlohmann::json& j, const std::filesystem::path& json_path, const std::string& report_dir,
               bool disabled, const std::string& command);

/// An image the minimal page shows when the template is missing.
struct FallbackImage {
  std::string caption;  // shown above the image; may be empty
  std::string src;      // relative to the report's directory
  std::string alt;
};

/// Writes `out`/index.html: the template with `title` and `j` embedded, or, without a report directory,
/// a minimal page with `fallback` images (and a warning naming `command`).
void write_report_html(const std::filesystem::path& out, const std::string& report_dir, const std::string& title,
                       const nlohmann::json& j, const std::vector<FallbackImage>& fallback,
                       const std::string& command);

}  // namespace envpis::app
