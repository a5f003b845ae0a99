#include "sweep/runner.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "sweep/report.h"
#include "sweep/results.h"
#include "util/error.h"
#include "util/file_io.h"

extern char** environ;

namespace gi::sweep {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

std::atomic<int> gStopSignal{0};
extern "C" void onStopSignal(int sig) { gStopSignal.store(sig); }

void writeJsonFile(const fs::path& path, const json& j) {
  writeAtomically(path, [&](const fs::path& tmp) {
    std::ofstream o(tmp);
    o << j.dump(2) << "\n";
    o.close();
    if (!o) throw Error("cannot write " + path.string());
  });
}

json readJsonFile(const fs::path& path) {
  try {
    return json::parse(readTextFile(path));
  } catch (const json::exception& e) {
    throw Error(path.string() + ": " + e.what());
  }
}

struct ChildResult {
  bool ok = false;
  std::string message;  // why it failed
};

// The line of a child's log that says why it failed: the last "gi: error:" line, else the last
// non-empty line.
std::string failureLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, lastError, lastLine;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    lastLine = line;
    if (line.find("error") != std::string::npos) lastError = line;
  }
  std::string s = lastError.empty() ? lastLine : lastError;
  if (s.size() > 500) s = s.substr(0, 500) + "...";
  return s;
}

// Runs this `gi` binary with `args` in its own process group, stdout and stderr to `log`.
ChildResult runChild(const std::vector<std::string>& args, const fs::path& log, double timeoutSeconds) {
  static const std::string self = fs::read_symlink("/proc/self/exe").string();
  std::vector<std::string> argvStrings{self};
  argvStrings.insert(argvStrings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : argvStrings) argv.push_back(s.data());
  argv.push_back(nullptr);
  {
    std::ofstream header(log);
    for (auto& s : argvStrings) header << (&s == &argvStrings[0] ? "" : " ") << s;
    header << "\n";
  }

  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, log.c_str(), O_WRONLY | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);
  pid_t pid = 0;
  int rc = posix_spawn(&pid, self.c_str(), &files, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attr);
  if (rc != 0) return {false, std::string("cannot start gi: ") + std::strerror(rc)};

  auto start = Clock::now();
  int status = 0;
  bool timedOut = false;
  for (;;) {
    pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) return {false, std::string("waitpid: ") + std::strerror(errno)};
    double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (gStopSignal.load() || (timeoutSeconds > 0 && elapsed > timeoutSeconds)) {
      timedOut = !gStopSignal.load();
      kill(-pid, SIGKILL);
      waitpid(pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (timedOut) return {false, "timed out after " + std::to_string(int(timeoutSeconds)) + " s"};
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return {true, ""};
  std::string why = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                      : std::string("killed by signal ") + strsignal(WTERMSIG(status));
  std::string line = failureLine(log);
  return {false, line.empty() ? why : why + ": " + line};
}

std::string formatDuration(double s) {
  int t = int(s + 0.5);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%d:%02d:%02d", t / 3600, t / 60 % 60, t % 60);
  return buf;
}

// Holds an exclusive lock on <dir>/.lock while a sweep or merge writes into the folder, so that
// a second `gi sweep` on the same folder stops with a message instead of racing the first.
class FolderLock {
public:
  explicit FolderLock(const fs::path& dir) {
    fs::create_directories(dir);
    fd_ = ::open((dir / ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Error("cannot create " + (dir / ".lock").string() + ": " + std::strerror(errno));
    if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw Error("another gi sweep is writing into '" + dir.string() + "' (it holds " + (dir / ".lock").string() + ")");
    }
  }
  ~FolderLock() { ::close(fd_); }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

private:
  int fd_ = -1;
};

// Makes `dir` hold `specJson`: creates it, or checks that it already holds the same spec.
void claimFolder(const fs::path& dir, const json& specJson) {
  fs::create_directories(dir / "runs");
  fs::path specFile = dir / "spec.json";
  if (fs::exists(specFile)) {
    if (readJsonFile(specFile) != specJson)
      throw Error("sweep folder '" + dir.string() + "' holds a different sweep (its spec.json differs); use another --out");
  } else {
    writeJsonFile(specFile, specJson);
  }
}

std::string resultStatus(const fs::path& resultFile) {
  if (!fs::exists(resultFile)) return "";
  try {
    return readJsonFile(resultFile).value("status", "");
  } catch (const Error&) {
    return "";  // unreadable: treat as not finished
  }
}

class SweepRunner {
public:
  SweepRunner(const Spec& spec, fs::path dir) : spec_(spec), dir_(std::move(dir)) {}

  // Returns the path of the configuration's reference (made on first use), or "" with a reason.
  std::string reference(const Configuration& c, std::string& whyNot) {
    if (!spec_.reference.enabled) return "";
    std::string key = referenceKey(c, spec_.reference);
    fs::path exr = dir_ / "references" / (key + ".exr"), failed = dir_ / "references" / (key + ".failed");
    if (fs::exists(exr)) return exr.string();
    if (fs::exists(failed)) {
      whyNot = "reference failed: " + readTextFile(failed);
      return "";
    }
    fs::create_directories(exr.parent_path());
    const int spp = spec_.reference.sppFor(c);
    std::fprintf(stderr, "sweep: path-tracing the reference %s (%d spp)\n", key.c_str(), spp);
    std::vector<std::string> args{"reference"};
    if (!c.scene.empty()) args.push_back(c.scene);
    if (!c.camera.empty()) args.insert(args.end(), {"--camera", c.camera});
    args.insert(args.end(), {"--width", std::to_string(c.width), "--height", std::to_string(c.height), "--spp",
                             std::to_string(spp), "--max-bounces", std::to_string(spec_.reference.maxBounces),
                             "--out", exr.string(), "--checkpoint", (dir_ / "references" / (key + ".checkpoint")).string()});
    if (!spec_.reference.device.empty()) args.insert(args.end(), {"--device", spec_.reference.device});
    if (!spec_.media.empty()) args.insert(args.end(), {"--media", spec_.media});
    ChildResult r = runChild(args, dir_ / "references" / (key + ".log"), 0);
    if (gStopSignal.load()) return "";
    if (r.ok && fs::exists(exr)) return exr.string();
    whyNot = "reference failed: " + r.message;
    std::ofstream(failed) << r.message;
    return "";
  }

  // Runs one configuration and records its result. Returns false if interrupted.
  bool run(const Configuration& c) {
    fs::path runDir = dir_ / "runs" / c.id;
    fs::create_directories(runDir);
    std::string whyNoReference;
    std::string ref = reference(c, whyNoReference);
    if (gStopSignal.load()) return false;
    // Paths inside the sweep folder are recorded relative to it, so that merged or moved sweeps keep them.
    const std::string rel = "runs/" + c.id + "/";
    std::vector<std::string> args{"bench"};
    if (!c.scene.empty()) args.push_back(c.scene);
    args.insert(args.end(), {"--technique", c.technique, "--width", std::to_string(c.width), "--height",
                             std::to_string(c.height), "--frames", std::to_string(c.frames), "--warmup",
                             std::to_string(c.warmup), "--json", (runDir / "bench.json").string(), "--image",
                             (runDir / "image.png").string()});
    if (!c.camera.empty()) args.insert(args.end(), {"--camera", c.camera});
    if (!c.device.empty()) args.insert(args.end(), {"--device", c.device});
    if (!spec_.media.empty()) args.insert(args.end(), {"--media", spec_.media});
    for (auto& [n, v] : c.params) args.insert(args.end(), {"--set", n + "=" + v});
    if (!ref.empty()) args.insert(args.end(), {"--reference", ref, "--heatmap", (runDir / "heatmap.png").string()});

    auto t0 = Clock::now();
    ChildResult r = runChild(args, runDir / "log.txt", spec_.timeoutSeconds);
    if (gStopSignal.load()) return false;
    if (r.ok && !fs::exists(runDir / "bench.json")) r = {false, "gi bench exited 0 but wrote no bench.json"};
    json result{{"configuration", c.toJson()},
                {"status", r.ok ? "ok" : "failed"},
                {"message", r.message},
                {"seconds", std::chrono::duration<double>(Clock::now() - t0).count()},
                {"log", rel + "log.txt"}};
    if (r.ok) {
      json bench = readJsonFile(runDir / "bench.json");
      bench["image"] = rel + "image.png";
      if (bench.contains("quality")) {
        bench["quality"]["heatmap"] = rel + "heatmap.png";
        bench["quality"]["reference"] = fs::relative(ref, dir_).string();
        bench["quality"]["reference_spp"] = spec_.reference.sppFor(c);
      }
      result["bench"] = bench;
    }
    if (!whyNoReference.empty()) result["quality_message"] = whyNoReference;
    writeJsonFile(runDir / "result.json", result);
    lastOk_ = r.ok;
    lastMessage_ = r.message;
    return true;
  }

  bool lastOk_ = true;
  std::string lastMessage_;

private:
  const Spec& spec_;
  fs::path dir_;
};

}  // namespace

int runSweep(const std::string& specPath, const RunOptions& o) {
  if (o.outDir.empty()) throw Error("sweep: --out DIR is required");
  json specJson;
  try {
    specJson = json::parse(readTextFile(specPath));
  } catch (const json::exception& e) {
    throw Error("sweep spec '" + specPath + "': " + e.what());
  }
  Spec spec = parseSpec(specJson);
  fs::path dir = o.outDir;
  FolderLock lock(dir);
  claimFolder(dir, specJson);

  std::vector<Configuration> todo = selectShard(spec.configurations, o.shard);
  size_t total = todo.size(), done = 0;
  std::vector<Configuration> pending;
  for (auto& c : todo) {
    std::string status = resultStatus(dir / "runs" / c.id / "result.json");
    if (status == "ok" || (status == "failed" && !o.retryFailed)) ++done;
    else pending.push_back(c);
  }
  std::fprintf(stderr, "sweep '%s': %zu configuration(s)%s, %zu already finished, %zu to run -> %s\n", spec.name.c_str(),
               total,
               o.shard.count > 1 ? (" in shard " + std::to_string(o.shard.index) + "/" + std::to_string(o.shard.count)).c_str() : "",
               done, pending.size(), dir.string().c_str());

  gStopSignal.store(0);
  struct sigaction sa {}, oldInt{}, oldTerm{};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &oldInt);
  sigaction(SIGTERM, &sa, &oldTerm);

  SweepRunner runner(spec, dir);
  auto t0 = Clock::now();
  size_t ranNow = 0;
  for (auto& c : pending) {
    auto tc = Clock::now();
    if (!runner.run(c)) break;
    ++ranNow;
    ++done;
    double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    double left = elapsed / ranNow * (pending.size() - ranNow);
    std::fprintf(stderr, "[%zu/%zu] %-6s %7.1f s  %s%s | elapsed %s, left ~%s\n", done, total,
                 runner.lastOk_ ? "ok" : "FAILED", std::chrono::duration<double>(Clock::now() - tc).count(),
                 c.describe().c_str(), runner.lastOk_ ? "" : (" — " + runner.lastMessage_).c_str(),
                 formatDuration(elapsed).c_str(), formatDuration(left).c_str());
  }
  sigaction(SIGINT, &oldInt, nullptr);
  sigaction(SIGTERM, &oldTerm, nullptr);
  int stop = gStopSignal.load();

  writeResultTables(dir.string());
  if (o.report && !stop) writeReport(dir.string());
  if (stop)
    throw Error("sweep interrupted (" + std::string(strsignal(stop)) + ") after " + std::to_string(done) + "/" +
                std::to_string(total) + " configurations; run the same command again to resume");

  int failed = 0;
  for (auto& c : todo)
    if (resultStatus(dir / "runs" / c.id / "result.json") == "failed") ++failed;
  std::fprintf(stderr, "sweep: %zu/%zu configuration(s) finished, %d failed; tables in %s\n", done, total, failed,
               dir.string().c_str());
  return failed;
}

void mergeSweeps(const std::vector<std::string>& dirs, const std::string& outDir, bool report) {
  if (dirs.empty()) throw Error("sweep --merge: name the sweep folders to merge");
  if (outDir.empty()) throw Error("sweep --merge: --out DIR is required");
  json specJson;
  for (auto& d : dirs) {
    fs::path specFile = fs::path(d) / "spec.json";
    if (!fs::exists(specFile)) throw Error("sweep --merge: '" + d + "' is not a sweep folder (no spec.json)");
    json s = readJsonFile(specFile);
    if (specJson.is_null()) specJson = s;
    else if (s != specJson) throw Error("sweep --merge: '" + d + "' ran a different spec than '" + dirs[0] + "'");
  }
  parseSpec(specJson);  // the same checks as a run
  fs::path out = outDir;
  FolderLock lock(out);
  claimFolder(out, specJson);
  std::map<std::string, std::string> chosenStatus;
  for (auto& e : fs::directory_iterator(out / "runs")) chosenStatus[e.path().filename()] = resultStatus(e.path() / "result.json");
  for (auto& d : dirs) {
    if (fs::equivalent(d, out)) continue;
    if (fs::exists(fs::path(d) / "runs"))
      for (auto& e : fs::directory_iterator(fs::path(d) / "runs")) {
        std::string id = e.path().filename(), status = resultStatus(e.path() / "result.json");
        if (status.empty()) continue;  // unfinished
        auto it = chosenStatus.find(id);
        if (it != chosenStatus.end() && !it->second.empty() && !(it->second == "failed" && status == "ok")) continue;
        fs::remove_all(out / "runs" / id);
        fs::copy(e.path(), out / "runs" / id, fs::copy_options::recursive);
        chosenStatus[id] = status;
      }
    if (fs::exists(fs::path(d) / "references")) {
      fs::create_directories(out / "references");
      fs::copy(fs::path(d) / "references", out / "references",
               fs::copy_options::recursive | fs::copy_options::skip_existing);
    }
  }
  writeResultTables(out.string());
  if (report) writeReport(out.string());
}

}  // namespace gi::sweep
