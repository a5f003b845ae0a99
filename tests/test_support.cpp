#include "test_support.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sys/wait.h>

namespace gi::test {

cl::Context& context() {
  static cl::Context ctx(cl::selectDevice(std::getenv("GI_DEVICE") ? "" : "cpu"));
  return ctx;
}

std::filesystem::path tempDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("gi_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

CommandResult runGi(const std::string& args, const std::string& envPrefix) {
  std::string cmd = envPrefix + " " + GI_BINARY + " " + args + " 2>&1";
  CommandResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) { r.exitCode = -1; return r; }
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  int status = pclose(p);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

RenderSettings smallRenderSettings(const std::string& technique, int width, int height, std::vector<std::string> sets) {
  RenderSettings rs;
  rs.width = width;
  rs.height = height;
  rs.technique = technique;
  rs.sets = std::move(sets);
  rs.sets.push_back("rsm.resolution=64");
  rs.sets.push_back("shadow.resolution=256");
  rs.sets.push_back("shadow.cube_resolution=128");
  return rs;
}

}  // namespace gi::test
