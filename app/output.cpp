#include "app/output.h"

#include <cerrno>
#include <cstdlib>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "analysis/error.h"

namespace pandora::app {

void PrepareOutputDir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw InputError(dir, "", "cannot create the output folder: " + ec.message(),
                     "choose another --out folder");
  if (!std::filesystem::is_directory(dir))
    throw InputError(dir, "", "the output path exists and is not a folder",
                     "choose another --out folder");
  const std::string probe = (std::filesystem::path(dir) / ".pandora-write-test.tmp").string();
  std::ofstream f(probe);
  if (!f)
    throw InputError(dir, "", "the output folder is not writable", "choose another --out folder");
  f.close();
  std::remove(probe.c_str());
}

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), active_(enabled && isatty(STDERR_FILENO)) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Update(double fraction) {
  if (!active_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (fraction < 1.0 && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const int width = 30;
  const int filled = static_cast<int>(fraction * width + 0.5);
  std::fprintf(stderr, "\r%s [%s%s] %3d%%", label_.c_str(), std::string(filled, '#').c_str(),
               std::string(width - filled, ' ').c_str(), static_cast<int>(fraction * 100 + 0.5));
  std::fflush(stderr);
}

void ProgressBar::Finish() {
  if (!active_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  std::fprintf(stderr, "\r%*s\r", static_cast<int>(label_.size()) + 40, "");
  std::fflush(stderr);
}

std::pair<int, int> ParseImageSize(const std::string& option, const std::string& text) {
  const std::string hint = "e.g. " + option + " 1280x720";
  const std::size_t x = text.find_first_of("xX");
  auto side = [&](const std::string& part) {
    char* end = nullptr;
    errno = 0;
    const long v = part.empty() ? 0 : std::strtol(part.c_str(), &end, 10);
    if (part.empty() || *end != '\0' || errno != 0 || v < 1 || v > 16384)
      throw InputError(option, "", "expected WIDTHxHEIGHT in pixels, 1 to 16384 each, got '" + text + "'",
                       hint);
    return static_cast<int>(v);
  };
  if (x == std::string::npos)
    throw InputError(option, "", "expected WIDTHxHEIGHT in pixels, got '" + text + "'", hint);
  const int w = side(text.substr(0, x)), h = side(text.substr(x + 1));
  if (static_cast<long long>(w) * h > 64LL * 1024 * 1024)
    throw InputError(option, "",
                     "'" + text + "' is " + std::to_string(static_cast<long long>(w) * h / 1000000) +
                         " Mpx; at most 64 Mpx (about 40 bytes per pixel with the float layers)",
                     hint);
  return {w, h};
}

void RefuseToOverwriteInputs(const Scene& scene, const std::string& out, const std::string& what) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(scene.path).parent_path();
  auto refuse_if = [&](const std::string& input, const char* kind) {
    if (input.empty()) return;
    fs::path p(input);
    if (p.is_relative()) p = folder / p;
    std::error_code ec;
    if (fs::equivalent(out, p, ec))
      throw InputError(out, "", what + " would overwrite the " + kind + " '" + input + "'",
                       "write the output to another file");
  };
  refuse_if(scene.path, "scene file");
  for (const SceneObject& o : scene.objects) refuse_if(o.source, "mesh file");
  for (const Material& m : scene.materials) refuse_if(m.texture, "texture");
}

}  // namespace pandora::app
