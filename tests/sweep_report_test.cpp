// The sweep report in a real browser: a tiny sweep with a path-traced reference (built-in Cornell
// box, 48x48, direct and vpl), its report.html rendered by headless Debian chromium to a
// screenshot, which must show the charts and images (not a blank page). setup.sh installs chromium.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "image/image.h"
#include "test_support.h"

using namespace gi;
namespace fs = std::filesystem;

namespace {

std::string findChromium() {
  for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"})
    if (fs::exists(p)) return p;
  return "";
}

}  // namespace

TEST(SweepReport, RendersInHeadlessChromium) {
  auto dir = test::tempDir("sweep_report");
  fs::path spec = dir / "spec.json";
  std::ofstream(spec) << R"({"name": "report test", "resolutions": ["48x48"], "frames": 2, "warmup": 1,
    "set": {"shadow.resolution": 256, "shadow.cube_resolution": 64, "rsm.resolution": 64},
    "reference": {"spp": 16, "max_bounces": 4},
    "techniques": ["direct", {"name": "vpl", "grid": {"vpl.count": [8, 32]}}]})";
  test::CommandResult r = test::runGi("sweep " + spec.string() + " --out " + (dir / "s").string(), "GI_DEVICE=cpu");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  fs::path html = dir / "s" / "report.html";
  ASSERT_TRUE(fs::exists(html)) << r.output;
  std::string page = test::readFile(html);
  // Self-contained: images inline, no external references.
  EXPECT_NE(page.find("<svg"), std::string::npos);
  EXPECT_NE(page.find("data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(page.find("src='runs/"), std::string::npos);
  EXPECT_EQ(page.find("http://"), page.find("http://www.w3.org/2000/svg"));  // only the SVG namespace
  EXPECT_NE(page.find("Pareto front"), std::string::npos);
  EXPECT_NE(page.find("<b>reference</b>"), std::string::npos);
  auto results = nlohmann::json::parse(std::ifstream(dir / "s" / "results.json"));
  for (auto& row : results["rows"]) {
    EXPECT_EQ(row["status"], "ok") << row.dump(2);
    EXPECT_TRUE(row["quality"]["flip"].is_number()) << row.dump(2);
  }

  std::string chromium = findChromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh test installs it); report not rendered";
  fs::path shot = dir / "shot.png";
  std::string cmd = "HOME=" + dir.string() + " timeout 120 " + chromium +
                    " --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1200,1600 --screenshot=" +
                    shot.string() + " file://" + html.string() + " > " + (dir / "chromium.log").string() + " 2>&1";
  int rc = std::system(cmd.c_str());
  ASSERT_EQ(rc, 0) << cmd << "\n" << test::readFile(dir / "chromium.log");
  ASSERT_TRUE(fs::exists(shot)) << test::readFile(dir / "chromium.log");
  Image img = readImage(shot);
  ASSERT_GT(img.width, 0);
  // Not blank: a good share of non-white pixels and many distinct colours (charts, images, text).
  size_t inked = 0;
  std::set<uint32_t> colours;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float* p = img.at(x, y);
      uint32_t c = 0;
      bool white = true;
      for (int k = 0; k < 3; ++k) {
        int v = int(p[std::min(k, img.channels - 1)] * 255.0f + 0.5f);
        c = c << 8 | uint32_t(v);
        white = white && v > 245;
      }
      inked += !white;
      colours.insert(c);
    }
  double share = double(inked) / img.pixelCount();
  EXPECT_GT(share, 0.03) << "screenshot mostly white: " << shot;
  EXPECT_GT(colours.size(), 200u) << "screenshot has few colours: " << shot;
  if (!HasFailure()) fs::remove_all(dir);
}
