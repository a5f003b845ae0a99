// The OpenCL layer: the only code in the engine that includes CL/cl.h.
//
// Device discovery and selection, one context + in-order profiling queue per device, program
// builds with an on-disk binary cache, RAII buffers, and named kernel launches whose device-side
// durations are collected by the Profiler (one line per kernel name in `--timings`).
#pragma once

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <CL/cl_ext.h>  // CL_PLATFORM_NOT_FOUND_KHR (ICD loader: no platform)

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "util/error.h"

namespace gi::cl {

// Throws gi::Error "what: CL_ERROR_NAME" when err != CL_SUCCESS.
void check(cl_int err, const std::string& what);
const char* errorName(cl_int err);

struct DeviceInfo {
  int index = 0;  // position in listDevices()
  cl_platform_id platform = nullptr;
  cl_device_id id = nullptr;
  std::string name, vendor, platformName, platformVersion, deviceVersion, driverVersion;
  bool isGpu = false, isCpu = false;
  uint64_t globalMemBytes = 0, maxAllocBytes = 0, localMemBytes = 0;
  uint64_t globalCacheBytes = 0;  // CL_DEVICE_GLOBAL_MEM_CACHE_SIZE (0: none or not reported)
  unsigned computeUnits = 0;
  bool imageSupport = false;
  bool image3dWrites = false;  // cl_khr_3d_image_writes
  bool int64Atomics = false;   // cl_khr_int64_base_atomics
  std::string describe() const;  // one line for `gi devices`
};

// All devices of all platforms. Throws gi::Error when there is no OpenCL platform at all.
std::vector<DeviceInfo> listDevices();

// selector: "" (use $GI_DEVICE, else the first GPU, else the first CPU), a device index,
// "cpu", "gpu", or a case-insensitive substring of the device or platform name.
DeviceInfo selectDevice(const std::string& selector);

class Context;

// A device buffer; frees itself. Moves, never copies.
class Buffer {
public:
  Buffer() = default;
  Buffer(Context& ctx, size_t bytes, cl_mem_flags flags = CL_MEM_READ_WRITE, const std::string& what = "buffer");
  ~Buffer();
  Buffer(Buffer&& o) noexcept : mem_(std::exchange(o.mem_, nullptr)), bytes_(std::exchange(o.bytes_, 0)) {}
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  cl_mem get() const { return mem_; }
  size_t bytes() const { return bytes_; }
  explicit operator bool() const { return mem_ != nullptr; }

private:
  cl_mem mem_ = nullptr;
  size_t bytes_ = 0;
};

// A kernel object with argument setting by position. Obtain from Program::kernel().
class Kernel {
public:
  Kernel() = default;
  Kernel(cl_kernel k, std::string name) : k_(k), name_(std::move(name)) {}
  ~Kernel();
  Kernel(Kernel&& o) noexcept : k_(std::exchange(o.k_, nullptr)), name_(std::move(o.name_)) {}
  Kernel& operator=(Kernel&& o) noexcept;
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  const std::string& name() const { return name_; }
  cl_kernel get() const { return k_; }

  template <typename... Args>
  Kernel& args(const Args&... a) {
    unsigned i = 0;
    (setArg(i++, a), ...);
    return *this;
  }
  void setArg(unsigned i, const Buffer& b) { cl_mem m = b.get(); setRaw(i, sizeof(cl_mem), &m); }
  struct Local { size_t bytes; };  // __local scratch of this size
  void setArg(unsigned i, Local l) { setRaw(i, l.bytes, nullptr); }
  template <typename T>
  void setArg(unsigned i, const T& v) { setRaw(i, sizeof(T), &v); }

private:
  void setRaw(unsigned i, size_t size, const void* ptr);
  cl_kernel k_ = nullptr;
  std::string name_;
};

class Program {
public:
  Program() = default;
  Program(cl_program p, std::string name) : p_(p), name_(std::move(name)) {}
  ~Program();
  Program(Program&& o) noexcept
      : p_(std::exchange(o.p_, nullptr)), name_(std::move(o.name_)), fromCache_(o.fromCache_) {}
  Program& operator=(Program&& o) noexcept;
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;

  Kernel kernel(const std::string& name) const;
  const std::string& name() const { return name_; }
  bool fromCache() const { return fromCache_; }
  void setFromCache(bool v) { fromCache_ = v; }

private:
  cl_program p_ = nullptr;
  std::string name_;
  bool fromCache_ = false;
};

// Compile-time defines for a program, e.g. {{"GI_TILE", "16"}}.
using Defines = std::vector<std::pair<std::string, std::string>>;

// Per-kernel device times, collected from profiling events. Launches are recorded in order;
// collect() waits for the queue and sums the durations by launch name.
class Profiler {
public:
  void record(const std::string& name, cl_event ev) { pending_.emplace_back(name, ev); }
  // Blocks until all recorded launches finished; returns (name, total ms) in first-launch order
  // and forgets the events.
  std::vector<std::pair<std::string, double>> collect();
  void discard();  // drop pending events without reading them (e.g. warm-up frames)
  ~Profiler() { discard(); }

private:
  std::vector<std::pair<std::string, cl_event>> pending_;
};

struct NDRange {
  size_t dims = 1;
  size_t global[3] = {1, 1, 1};
  size_t local[3] = {0, 0, 0};  // 0 = let the driver choose
  static NDRange d1(size_t g, size_t l = 0) { NDRange r; r.dims = 1; r.global[0] = g; r.local[0] = l; return r; }
  static NDRange d2(size_t gx, size_t gy, size_t lx = 0, size_t ly = 0) {
    NDRange r; r.dims = 2; r.global[0] = gx; r.global[1] = gy; r.local[0] = lx; r.local[1] = ly; return r;
  }
  static NDRange d3(size_t gx, size_t gy, size_t gz) {
    NDRange r; r.dims = 3; r.global[0] = gx; r.global[1] = gy; r.global[2] = gz; return r;
  }
};

inline size_t roundUp(size_t v, size_t m) { return (v + m - 1) / m * m; }

class Context {
public:
  explicit Context(const DeviceInfo& device);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& device() const { return device_; }
  cl_context get() const { return ctx_; }
  cl_command_queue queue() const { return queue_; }
  Profiler& profiler() { return profiler_; }

  // Pixels (or items) handled by one work-item in the vectorised kernels: 16 on a CPU device
  // (PoCL vectorises explicit float16 well, and loops over work-items not at all), 1 on a GPU.
  // $GI_VECTOR_WIDTH (1, 8 or 16) overrides it, so the GPU code paths can be tested on PoCL.
  int vectorWidth() const { return vectorWidth_; }

  // Builds kernels/<file> (includes expanded) with the given defines plus the per-device ones
  // (GI_VW, GI_DEVICE_CPU/GPU, GI_CPU_AMD). Uses the on-disk binary cache. Build failures throw gi::Error
  // with the compiler's messages, which name kernel file:line.
  Program buildProgram(const std::string& kernelFile, const Defines& defines = {});

  // Launches a kernel and records its device time under its name (or `label` if given).
  void launch(const Kernel& k, const NDRange& range, const std::string& label = {});

  // Blocking transfers. Reading back per frame is slow on PoCL: keep it to results.
  void write(const Buffer& b, const void* src, size_t bytes, size_t offset = 0);
  void read(const Buffer& b, void* dst, size_t bytes, size_t offset = 0);
  template <typename T>
  Buffer upload(const std::vector<T>& v, const std::string& what, cl_mem_flags flags = CL_MEM_READ_ONLY) {
    Buffer b(*this, std::max<size_t>(1, v.size()) * sizeof(T), flags, what);
    if (!v.empty()) write(b, v.data(), v.size() * sizeof(T));
    return b;
  }
  template <typename T>
  std::vector<T> download(const Buffer& b) {
    std::vector<T> v(b.bytes() / sizeof(T));
    if (!v.empty()) read(b, v.data(), v.size() * sizeof(T));
    return v;
  }
  void fill(const Buffer& b, const void* pattern, size_t patternBytes, size_t bytes = 0);
  template <typename T>
  void fill(const Buffer& b, T value) { fill(b, &value, sizeof(T)); }
  void copy(const Buffer& src, const Buffer& dst, size_t bytes, size_t srcOffset = 0, size_t dstOffset = 0);
  void finish();

  // Throws gi::Error naming `what` when `bytes` exceed what one allocation or the device can hold.
  void requireAllocation(uint64_t bytes, const std::string& what) const;

  // Whether large buffers live in host memory backed by 2 MiB pages (Linux, CPU devices; see
  // Buffer::Buffer). $GI_HUGE_PAGES=0 turns it off, e.g. to measure what it gives.
  bool hugePageBuffers() const { return hugePageBuffers_; }

  // Where compiled program binaries are kept: $GI_CACHE_DIR, else $XDG_CACHE_HOME/gi-engine,
  // else ~/.cache/gi-engine. Empty string disables the cache (GI_CACHE_DIR=off).
  static std::string cacheDirectory();

private:
  DeviceInfo device_;
  int vectorWidth_ = 1;
  bool hugePageBuffers_ = false;
  cl_context ctx_ = nullptr;
  cl_command_queue queue_ = nullptr;
  Profiler profiler_;
};

}  // namespace gi::cl
