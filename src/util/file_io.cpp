#include "util/file_io.h"

#include <fstream>
#include <sstream>
#include <unistd.h>

#include "util/error.h"

namespace gi {

std::string readTextFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open '" + path.string() + "'");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path&)>& write) {
  namespace fs = std::filesystem;
  fs::path dir = path.parent_path();
  if (!dir.empty() && !fs::exists(dir)) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw Error("cannot create directory '" + dir.string() + "': " + ec.message());
  }
  // Keep the extension last so format-by-extension writers (OpenImageIO) still recognise it.
  fs::path tmp = path;
  tmp.replace_filename("." + path.stem().string() + ".tmp" + std::to_string(::getpid()) +
                       path.extension().string());
  try {
    write(tmp);
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw Error("cannot write '" + path.string() + "': " + ec.message());
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

}  // namespace gi
