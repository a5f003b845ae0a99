#include "cl/runtime.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "cl/gather_width.h"
#include "cl/kernel_sources.h"
#include "util/file_io.h"
#include "util/hash.h"

namespace gi::cl {

const char* errorName(cl_int err) {
  switch (err) {
#define GI_CL_ERR(e) case e: return #e;
    GI_CL_ERR(CL_SUCCESS) GI_CL_ERR(CL_DEVICE_NOT_FOUND) GI_CL_ERR(CL_DEVICE_NOT_AVAILABLE)
    GI_CL_ERR(CL_COMPILER_NOT_AVAILABLE) GI_CL_ERR(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    GI_CL_ERR(CL_OUT_OF_RESOURCES) GI_CL_ERR(CL_OUT_OF_HOST_MEMORY) GI_CL_ERR(CL_PROFILING_INFO_NOT_AVAILABLE)
    GI_CL_ERR(CL_BUILD_PROGRAM_FAILURE) GI_CL_ERR(CL_INVALID_VALUE) GI_CL_ERR(CL_INVALID_DEVICE)
    GI_CL_ERR(CL_INVALID_CONTEXT) GI_CL_ERR(CL_INVALID_COMMAND_QUEUE) GI_CL_ERR(CL_INVALID_MEM_OBJECT)
    GI_CL_ERR(CL_INVALID_BINARY) GI_CL_ERR(CL_INVALID_BUILD_OPTIONS) GI_CL_ERR(CL_INVALID_PROGRAM)
    GI_CL_ERR(CL_INVALID_KERNEL_NAME) GI_CL_ERR(CL_INVALID_KERNEL) GI_CL_ERR(CL_INVALID_ARG_INDEX)
    GI_CL_ERR(CL_INVALID_ARG_VALUE) GI_CL_ERR(CL_INVALID_ARG_SIZE) GI_CL_ERR(CL_INVALID_KERNEL_ARGS)
    GI_CL_ERR(CL_INVALID_WORK_DIMENSION) GI_CL_ERR(CL_INVALID_WORK_GROUP_SIZE)
    GI_CL_ERR(CL_INVALID_WORK_ITEM_SIZE) GI_CL_ERR(CL_INVALID_GLOBAL_OFFSET) GI_CL_ERR(CL_INVALID_EVENT)
    GI_CL_ERR(CL_INVALID_BUFFER_SIZE) GI_CL_ERR(CL_INVALID_GLOBAL_WORK_SIZE) GI_CL_ERR(CL_INVALID_PLATFORM)
    GI_CL_ERR(CL_PLATFORM_NOT_FOUND_KHR)
#undef GI_CL_ERR
    default: return "CL_UNKNOWN_ERROR";
  }
}

void check(cl_int err, const std::string& what) {
  if (err != CL_SUCCESS) throw Error(what + ": " + errorName(err) + " (" + std::to_string(err) + ")");
}

namespace {

std::string deviceString(cl_device_id d, cl_device_info p) {
  size_t n = 0;
  clGetDeviceInfo(d, p, 0, nullptr, &n);
  std::string s(n, '\0');
  clGetDeviceInfo(d, p, n, s.data(), nullptr);
  while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
  return s;
}
std::string platformString(cl_platform_id pl, cl_platform_info p) {
  size_t n = 0;
  clGetPlatformInfo(pl, p, 0, nullptr, &n);
  std::string s(n, '\0');
  clGetPlatformInfo(pl, p, n, s.data(), nullptr);
  while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
  return s;
}
template <typename T>
T deviceValue(cl_device_id d, cl_device_info p) {
  T v{};
  clGetDeviceInfo(d, p, sizeof(T), &v, nullptr);
  return v;
}
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

}  // namespace

std::string DeviceInfo::describe() const {
  std::ostringstream s;
  s << "[" << index << "] " << name << " (" << (isGpu ? "GPU" : isCpu ? "CPU" : "other") << ", "
    << platformName << ", driver " << driverVersion << ", " << computeUnits << " compute units, "
    << globalMemBytes / (1024 * 1024) << " MiB, max alloc " << maxAllocBytes / (1024 * 1024) << " MiB"
    << (image3dWrites ? ", 3D image writes" : "") << (int64Atomics ? ", 64-bit atomics" : "") << ")";
  return s.str();
}

std::vector<DeviceInfo> listDevices() {
  cl_uint numPlatforms = 0;
  cl_int err = clGetPlatformIDs(0, nullptr, &numPlatforms);
  if (err == CL_PLATFORM_NOT_FOUND_KHR || numPlatforms == 0)
    throw Error("no OpenCL platform found (install an OpenCL driver, e.g. Debian's pocl-opencl-icd, "
                "and check /etc/OpenCL/vendors or OCL_ICD_VENDORS)");
  check(err, "clGetPlatformIDs");
  std::vector<cl_platform_id> platforms(numPlatforms);
  check(clGetPlatformIDs(numPlatforms, platforms.data(), nullptr), "clGetPlatformIDs");
  std::vector<DeviceInfo> out;
  for (cl_platform_id pl : platforms) {
    cl_uint n = 0;
    if (clGetDeviceIDs(pl, CL_DEVICE_TYPE_ALL, 0, nullptr, &n) != CL_SUCCESS || n == 0) continue;
    std::vector<cl_device_id> ids(n);
    if (clGetDeviceIDs(pl, CL_DEVICE_TYPE_ALL, n, ids.data(), nullptr) != CL_SUCCESS) continue;
    for (cl_device_id id : ids) {
      DeviceInfo d;
      d.index = static_cast<int>(out.size());
      d.platform = pl;
      d.id = id;
      d.name = deviceString(id, CL_DEVICE_NAME);
      d.vendor = deviceString(id, CL_DEVICE_VENDOR);
      d.deviceVersion = deviceString(id, CL_DEVICE_VERSION);
      d.driverVersion = deviceString(id, CL_DRIVER_VERSION);
      d.platformName = platformString(pl, CL_PLATFORM_NAME);
      d.platformVersion = platformString(pl, CL_PLATFORM_VERSION);
      auto type = deviceValue<cl_device_type>(id, CL_DEVICE_TYPE);
      d.isGpu = (type & CL_DEVICE_TYPE_GPU) != 0;
      d.isCpu = (type & CL_DEVICE_TYPE_CPU) != 0;
      d.globalMemBytes = deviceValue<cl_ulong>(id, CL_DEVICE_GLOBAL_MEM_SIZE);
      d.globalCacheBytes = deviceValue<cl_ulong>(id, CL_DEVICE_GLOBAL_MEM_CACHE_SIZE);
      d.maxAllocBytes = deviceValue<cl_ulong>(id, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      d.localMemBytes = deviceValue<cl_ulong>(id, CL_DEVICE_LOCAL_MEM_SIZE);
      d.computeUnits = deviceValue<cl_uint>(id, CL_DEVICE_MAX_COMPUTE_UNITS);
      d.imageSupport = deviceValue<cl_bool>(id, CL_DEVICE_IMAGE_SUPPORT) != 0;
      std::string ext = deviceString(id, CL_DEVICE_EXTENSIONS);
      d.image3dWrites = ext.find("cl_khr_3d_image_writes") != std::string::npos;
      d.int64Atomics = ext.find("cl_khr_int64_base_atomics") != std::string::npos;
      out.push_back(std::move(d));
    }
  }
  if (out.empty()) throw Error("OpenCL platforms were found but they have no devices");
  return out;
}

DeviceInfo selectDevice(const std::string& selectorIn) {
  std::vector<DeviceInfo> devices = listDevices();
  std::string selector = selectorIn;
  if (selector.empty())
    if (const char* env = std::getenv("GI_DEVICE")) selector = env;
  if (selector.empty()) {
    for (auto& d : devices) if (d.isGpu) return d;
    for (auto& d : devices) if (d.isCpu) return d;
    return devices.front();
  }
  std::string sel = lower(selector);
  if (sel == "gpu" || sel == "cpu") {
    for (auto& d : devices) if ((sel == "gpu" && d.isGpu) || (sel == "cpu" && d.isCpu)) return d;
    throw Error("device selector '" + selector + "': no " + sel + " device (see `gi devices`)");
  }
  if (std::all_of(sel.begin(), sel.end(), [](unsigned char c) { return std::isdigit(c); })) {
    size_t i = std::stoul(sel);
    if (i < devices.size()) return devices[i];
    throw Error("device selector '" + selector + "': index out of range, " + std::to_string(devices.size()) +
                " device(s) (see `gi devices`)");
  }
  for (auto& d : devices)
    if (lower(d.name).find(sel) != std::string::npos || lower(d.platformName).find(sel) != std::string::npos) return d;
  throw Error("device selector '" + selector + "' matches no device (see `gi devices`)");
}

// ---------------------------------------------------------------------------------------------
namespace {

// On a CPU device a kernel walking a large grid or record array touches a new 4 KiB page every
// few accesses, and with transparent huge pages in `madvise` mode (the Debian default) the
// driver's own allocations never get 2 MiB pages: the page walks showed up as a third of the
// voxel light injection's time (docs/PERFORMANCE.md). Buffers of at least this size are
// therefore allocated here, 2 MiB aligned and advised as huge pages, and handed to the driver
// with CL_MEM_USE_HOST_PTR (which a CPU driver uses in place).
constexpr size_t kHugePage = size_t(2) << 20;

#if defined(__linux__)
void* allocateHugePageMemory(size_t bytes) {
  void* p = nullptr;
  if (posix_memalign(&p, kHugePage, (bytes + kHugePage - 1) / kHugePage * kHugePage) != 0) return nullptr;
  madvise(p, bytes, MADV_HUGEPAGE);  // advice only: on failure the memory keeps 4 KiB pages
  return p;
}
void CL_CALLBACK freeHugePageMemory(cl_mem, void* p) { std::free(p); }
#endif

}  // namespace

Buffer::Buffer(Context& ctx, size_t bytes, cl_mem_flags flags, const std::string& what) : bytes_(bytes) {
  ctx.requireAllocation(bytes, what);
  const std::string failure = "allocating " + what + " (" + std::to_string(bytes) + " bytes)";
  cl_int err = CL_SUCCESS;
#if defined(__linux__)
  if (ctx.hugePageBuffers() && bytes >= kHugePage) {
    void* host = allocateHugePageMemory(bytes);
    if (!host) throw Error(failure + ": out of host memory");
    mem_ = clCreateBuffer(ctx.get(), flags | CL_MEM_USE_HOST_PTR, bytes, host, &err);
    if (err == CL_SUCCESS) err = clSetMemObjectDestructorCallback(mem_, freeHugePageMemory, host);
    if (err != CL_SUCCESS) {
      if (mem_) clReleaseMemObject(std::exchange(mem_, nullptr));
      std::free(host);
    }
    check(err, failure);
    return;
  }
#endif
  mem_ = clCreateBuffer(ctx.get(), flags, std::max<size_t>(bytes, 1), nullptr, &err);
  check(err, failure);
}
Buffer::~Buffer() { if (mem_) clReleaseMemObject(mem_); }
Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    if (mem_) clReleaseMemObject(mem_);
    mem_ = std::exchange(o.mem_, nullptr);
    bytes_ = std::exchange(o.bytes_, 0);
  }
  return *this;
}

Kernel::~Kernel() { if (k_) clReleaseKernel(k_); }
Kernel& Kernel::operator=(Kernel&& o) noexcept {
  if (this != &o) {
    if (k_) clReleaseKernel(k_);
    k_ = std::exchange(o.k_, nullptr);
    name_ = std::move(o.name_);
  }
  return *this;
}
void Kernel::setRaw(unsigned i, size_t size, const void* ptr) {
  check(clSetKernelArg(k_, i, size, ptr), "kernel " + name_ + " argument " + std::to_string(i));
}

Program::~Program() { if (p_) clReleaseProgram(p_); }
Program& Program::operator=(Program&& o) noexcept {
  if (this != &o) {
    if (p_) clReleaseProgram(p_);
    p_ = std::exchange(o.p_, nullptr);
    name_ = std::move(o.name_);
    fromCache_ = o.fromCache_;
  }
  return *this;
}
Kernel Program::kernel(const std::string& name) const {
  cl_int err = CL_SUCCESS;
  cl_kernel k = clCreateKernel(p_, name.c_str(), &err);
  check(err, "kernel '" + name + "' in " + name_);
  return Kernel(k, name);
}

// ---------------------------------------------------------------------------------------------
std::vector<std::pair<std::string, double>> Profiler::collect() {
  std::vector<std::pair<std::string, double>> out;
  for (auto& [name, ev] : pending_) {
    clWaitForEvents(1, &ev);
    cl_ulong t0 = 0, t1 = 0;
    clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_START, sizeof t0, &t0, nullptr);
    clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_END, sizeof t1, &t1, nullptr);
    clReleaseEvent(ev);
    double ms = t1 > t0 ? (t1 - t0) * 1e-6 : 0.0;
    auto it = std::find_if(out.begin(), out.end(), [&](auto& p) { return p.first == name; });
    if (it == out.end()) out.emplace_back(name, ms);
    else it->second += ms;
  }
  pending_.clear();
  return out;
}
void Profiler::discard() {
  for (auto& p : pending_) {
    clWaitForEvents(1, &p.second);
    clReleaseEvent(p.second);
  }
  pending_.clear();
}

// ---------------------------------------------------------------------------------------------
int gatherVectorWidth(const Context& ctx) {
  if (const char* vw = std::getenv("GI_VECTOR_WIDTH"); vw && *vw) return ctx.vectorWidth();
  if (!ctx.device().isCpu) return ctx.vectorWidth();
  cl_uint native = deviceValue<cl_uint>(ctx.device().id, CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT);
  return native >= 16 ? 16 : 8;
}

Defines withGatherWidth(const Context& ctx, Defines defines) {
  defines.emplace_back("GI_VW", std::to_string(gatherVectorWidth(ctx)));
  return defines;
}

Context::Context(const DeviceInfo& device) : device_(device) {
  vectorWidth_ = device_.isCpu ? 16 : 1;
  if (const char* vw = std::getenv("GI_VECTOR_WIDTH"); vw && *vw) {
    std::string v = vw;
    if (v != "1" && v != "8" && v != "16") throw Error("GI_VECTOR_WIDTH='" + v + "': expected 1, 8 or 16");
    vectorWidth_ = std::stoi(v);
  }
#if defined(__linux__)
  hugePageBuffers_ = device_.isCpu;
#endif
  if (const char* hp = std::getenv("GI_HUGE_PAGES"); hp && *hp) {
    std::string v = hp;
    if (v != "0" && v != "1") throw Error("GI_HUGE_PAGES='" + v + "': expected 0 or 1");
    hugePageBuffers_ = hugePageBuffers_ && v == "1";
  }
  cl_int err = CL_SUCCESS;
  cl_context_properties props[] = {CL_CONTEXT_PLATFORM, reinterpret_cast<cl_context_properties>(device.platform), 0};
  ctx_ = clCreateContext(props, 1, &device_.id, nullptr, nullptr, &err);
  check(err, "creating an OpenCL context on " + device_.name);
  queue_ = clCreateCommandQueue(ctx_, device_.id, CL_QUEUE_PROFILING_ENABLE, &err);
  if (err != CL_SUCCESS) {
    clReleaseContext(ctx_);
    check(err, "creating a command queue on " + device_.name);
  }
}
Context::~Context() {
  profiler_.discard();
  if (queue_) { clFinish(queue_); clReleaseCommandQueue(queue_); }
  if (ctx_) clReleaseContext(ctx_);
}

std::string Context::cacheDirectory() {
  if (const char* d = std::getenv("GI_CACHE_DIR"); d && *d) return std::string(d) == "off" ? "" : d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return std::string(d) + "/gi-engine";
  if (const char* d = std::getenv("HOME"); d && *d) return std::string(d) + "/.cache/gi-engine";
  return "";
}

namespace {

// Keeps the lines of a build log that matter (errors and their context), at most ~60 lines.
std::string trimBuildLog(const std::string& log) {
  std::istringstream in(log);
  std::string line, out;
  int n = 0;
  while (std::getline(in, line) && n < 60) {
    if (line.empty()) continue;
    out += "  " + line + "\n";
    ++n;
  }
  return out;
}

std::string buildLog(cl_program p, cl_device_id d) {
  size_t n = 0;
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n);
  std::string s(n, '\0');
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, n, s.data(), nullptr);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

}  // namespace

Program Context::buildProgram(const std::string& kernelFile, const Defines& defines) {
  std::string source = expandKernelIncludes(kernelFile);
  std::string options = "-cl-std=CL1.2 -cl-mad-enable -cl-no-signed-zeros";
  // A GI_VW among the defines (cl/gather_width.h) replaces the context's default lane count.
  bool ownWidth = std::any_of(defines.begin(), defines.end(), [](const auto& d) { return d.first == "GI_VW"; });
  if (!ownWidth) options += " -DGI_VW=" + std::to_string(vectorWidth());
  options += device_.isCpu ? " -DGI_DEVICE_CPU=1" : " -DGI_DEVICE_GPU=1";
  // Kernels that pick a CPU-specific instruction form by measurement (rsm_gather.cl) need to know
  // whose CPU it is: the same AVX-512 instruction can be the fast form on one vendor's cores and
  // the slow one on another's.
  if (device_.isCpu && device_.vendor.find("AMD") != std::string::npos) options += " -DGI_CPU_AMD=1";
  for (auto& [k, v] : defines) options += " -D" + k + (v.empty() ? "" : "=" + v);

  uint64_t key = fnv1a64(source);
  key = fnv1a64(options, key);
  key = fnv1a64(device_.name + "|" + device_.driverVersion + "|" + device_.platformVersion + "|" + device_.deviceVersion, key);
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(key));
  std::string dir = cacheDirectory();
  std::filesystem::path cacheFile = dir.empty() ? std::filesystem::path() : std::filesystem::path(dir) / (std::string(hex) + ".bin");

  cl_int err = CL_SUCCESS;
  // Warm start: load the binary the driver produced last time.
  if (!cacheFile.empty() && std::filesystem::exists(cacheFile)) {
    std::ifstream in(cacheFile, std::ios::binary);
    std::vector<unsigned char> bin((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const unsigned char* ptr = bin.data();
    size_t len = bin.size();
    cl_int binStatus = CL_SUCCESS;
    cl_program p = bin.empty() ? nullptr : clCreateProgramWithBinary(ctx_, 1, &device_.id, &len, &ptr, &binStatus, &err);
    if (p && err == CL_SUCCESS && binStatus == CL_SUCCESS &&
        clBuildProgram(p, 1, &device_.id, options.c_str(), nullptr, nullptr) == CL_SUCCESS) {
      Program prog(p, kernelFile);
      prog.setFromCache(true);
      return prog;
    }
    if (p) clReleaseProgram(p);
    std::error_code ec;
    std::filesystem::remove(cacheFile, ec);  // stale or corrupt: rebuild from source
  }

  const char* src = source.c_str();
  size_t len = source.size();
  cl_program p = clCreateProgramWithSource(ctx_, 1, &src, &len, &err);
  check(err, "creating program " + kernelFile);
  err = clBuildProgram(p, 1, &device_.id, options.c_str(), nullptr, nullptr);
  if (err != CL_SUCCESS) {
    std::string log = buildLog(p, device_.id);
    clReleaseProgram(p);
    throw Error("kernel build failed: " + kernelFile + " on " + device_.name + " (" + errorName(err) + ")\n" +
                trimBuildLog(log));
  }
  if (!cacheFile.empty()) {
    size_t binSize = 0;
    clGetProgramInfo(p, CL_PROGRAM_BINARY_SIZES, sizeof binSize, &binSize, nullptr);
    if (binSize > 0) {
      std::vector<unsigned char> bin(binSize);
      unsigned char* ptr = bin.data();
      if (clGetProgramInfo(p, CL_PROGRAM_BINARIES, sizeof ptr, &ptr, nullptr) == CL_SUCCESS) {
        try {
          writeAtomically(cacheFile, [&](const std::filesystem::path& tmp) {
            std::ofstream out(tmp, std::ios::binary);
            out.write(reinterpret_cast<const char*>(bin.data()), static_cast<std::streamsize>(bin.size()));
            if (!out) throw Error("cannot write " + tmp.string());
          });
        } catch (const Error& e) {
          warn(std::string("program cache not written: ") + e.what());
        }
      }
    }
  }
  return Program(p, kernelFile);
}

void Context::launch(const Kernel& k, const NDRange& r, const std::string& label) {
  size_t global[3];
  bool hasLocal = r.local[0] != 0;
  for (size_t i = 0; i < r.dims; ++i) global[i] = hasLocal ? roundUp(r.global[i], r.local[i]) : r.global[i];
  cl_event ev = nullptr;
  cl_int err = clEnqueueNDRangeKernel(queue_, k.get(), static_cast<cl_uint>(r.dims), nullptr, global,
                                      hasLocal ? r.local : nullptr, 0, nullptr, &ev);
  check(err, "launching kernel " + (label.empty() ? k.name() : label));
  profiler_.record(label.empty() ? k.name() : label, ev);
}

void Context::write(const Buffer& b, const void* src, size_t bytes, size_t offset) {
  check(clEnqueueWriteBuffer(queue_, b.get(), CL_TRUE, offset, bytes, src, 0, nullptr, nullptr), "writing a device buffer");
}
void Context::read(const Buffer& b, void* dst, size_t bytes, size_t offset) {
  check(clEnqueueReadBuffer(queue_, b.get(), CL_TRUE, offset, bytes, dst, 0, nullptr, nullptr), "reading a device buffer");
}
void Context::fill(const Buffer& b, const void* pattern, size_t patternBytes, size_t bytes) {
  if (bytes == 0) bytes = b.bytes() / patternBytes * patternBytes;
  check(clEnqueueFillBuffer(queue_, b.get(), pattern, patternBytes, 0, bytes, 0, nullptr, nullptr), "filling a device buffer");
}
void Context::copy(const Buffer& src, const Buffer& dst, size_t bytes, size_t srcOffset, size_t dstOffset) {
  check(clEnqueueCopyBuffer(queue_, src.get(), dst.get(), srcOffset, dstOffset, bytes, 0, nullptr, nullptr),
        "copying a device buffer");
}
void Context::finish() { check(clFinish(queue_), "waiting for the device"); }

void Context::requireAllocation(uint64_t bytes, const std::string& what) const {
  auto mib = [](uint64_t b) { return std::to_string(b / (1024 * 1024)) + " MiB"; };
  if (bytes > device_.maxAllocBytes)
    throw Error(what + " needs " + mib(bytes) + " in one allocation, more than " + device_.name + " allows (" +
                mib(device_.maxAllocBytes) + "); reduce the resolution or scene size");
  if (bytes > device_.globalMemBytes)
    throw Error(what + " needs " + mib(bytes) + ", more than the memory of " + device_.name);
}

}  // namespace gi::cl
