// SPDX-License-Identifier: Apache-2.0
#include "report.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "envpis/envpis.h"

extern char** environ;

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

/// Runs argv (argv[0] looked up on PATH); returns the exit status, 127 when it could not start.
int run_process(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, args[0], nullptr, nullptr, args.data(), environ) != 0) return 127;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return 127;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

std::string executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : exe.parent_path().string();
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error("cannot read '" + p.string() + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  for (std::size_t pos = 0; (pos = s.find(from, pos)) != std::string::npos; pos += to.size()) s.replace(pos, from.size(), to);
}

/// JSON safe to embed inside <script type="application/json">: no "</" sequences.
std::string json_for_script(const json& j) {
  std::string s = j.dump();
  replace_all(s, "</", "<\\/");
  replace_all(s, "<!--", "<\\!--");
  return s;
}

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

/// Runs plots.py with the first python that has matplotlib; returns why there are no plots (empty when
/// there are, with `manifest` read).
std::string run_plots(const fs::path& json_path, const std::string& report_dir, json& manifest) {
  std::vector<std::string> pythons;
  if (const char* p = std::getenv("ENVPIS_PYTHON"); p && *p) pythons.emplace_back(p);
  pythons.emplace_back("/usr/bin/python3");  // Debian's, where python3-matplotlib lives
  pythons.emplace_back("python3");
  const fs::path manifest_path = json_path.parent_path() / "plots" / "manifest.json";
  std::error_code ec;
  fs::remove(manifest_path, ec);
  int status = 127;
  for (const auto& py : pythons) {
    if (py.find('/') != std::string::npos && !fs::exists(py, ec)) continue;
    status = run_process({py, (fs::path(report_dir) / "plots.py").string(), json_path.string()});
    if (status == 0 || (status != 3 && status != 127)) break;  // 3: no matplotlib, 127: no python: try the next
  }
  if (status == 0 && fs::exists(manifest_path, ec)) {
    try {
      std::ifstream in(manifest_path);
      in >> manifest;
      return "";
    } catch (const std::exception& e) {
      return std::string("plots manifest unreadable: ") + e.what();
    }
  }
  if (status == 3 || status == 127) return "python3 with matplotlib not found (install python3-matplotlib)";
  return "report/plots.py failed (exit status " + std::to_string(status) + ")";
}

std::string minimal_page(const std::string& command, const std::vector<FallbackImage>& images) {
  std::string html = "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>envpis " + command +
                     "</title></head><body><h1>envpis " + command +
                     "</h1><p>The report template was not found; see metrics.json.</p>";
  for (const FallbackImage& im : images)
    html += "<p>" + (im.caption.empty() ? std::string() : im.caption + "<br>") + "<img src=\"" + im.src +
            "\" alt=\"" + im.alt + "\"></p>";
  return html + "</body></html>\n";
}

}  // namespace

std::string find_report_dir(const std::string& option) {
  auto ok = [](const fs::path& d) {
    std::error_code ec;
    return fs::is_regular_file(d / "template.html", ec);
  };
  if (!option.empty()) {
    if (!ok(option)) throw Error("--report-dir '" + option + "' has no template.html");
    return option;
  }
  std::vector<fs::path> candidates;
  if (const char* e = std::getenv("ENVPIS_REPORT_DIR"); e && *e) candidates.emplace_back(e);
  candidates.push_back(fs::path(ENVPIS_SOURCE_DIR) / "report");
  const std::string exe = executable_dir();
  if (!exe.empty()) candidates.push_back(fs::path(exe).parent_path() / "share" / "envpis" / "report");
  for (const auto& c : candidates)
    if (ok(c)) return c.string();
  return "";
}

void add_plots(json& j, const fs::path& json_path, const std::string& report_dir, bool disabled,
               const std::string& command) {
  json manifest;
  std::string problem;
  if (disabled)
    problem = "plots disabled (--no-plots)";
  else if (report_dir.empty())
    problem = "report/plots.py not found (set ENVPIS_REPORT_DIR or --report-dir)";
  else
    problem = run_plots(json_path, report_dir, manifest);
  if (problem.empty()) {
    j["plots"] = manifest;
    return;
  }
  j["plots"] = nullptr;
  j["plots_unavailable"] = problem;
  if (!disabled)
    std::fprintf(stderr, "envpis %s: warning: %s; images and %s are written, the report has no plots\n",
                 command.c_str(), problem.c_str(), json_path.filename().c_str());
}

void write_report_html(const fs::path& out, const std::string& report_dir, const std::string& title, const json& j,
                       const std::vector<FallbackImage>& fallback, const std::string& command) {
  std::string html;
  if (!report_dir.empty()) {
    html = read_text(fs::path(report_dir) / "template.html");
    replace_all(html, "{{STYLE}}", read_text(fs::path(report_dir) / "report.css"));
    replace_all(html, "{{SCRIPT}}", read_text(fs::path(report_dir) / "report.js"));
    replace_all(html, "{{TITLE}}", html_escape(title));
    replace_all(html, "{{METRICS_JSON}}", json_for_script(j));
  } else {
    std::fprintf(stderr, "envpis %s: warning: report/template.html not found; writing a minimal index.html\n",
                 command.c_str());
    html = minimal_page(command, fallback);
  }
  std::ofstream(out / "index.html") << html;
}

}  // namespace envpis::app
