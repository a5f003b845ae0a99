// Force-included into every kernel when the tests run under Oclgrind (README, "Development notes"):
//   OCLGRIND_BUILD_OPTIONS="-include $PWD/tests/oclgrind/builtin_workarounds.h" oclgrind ...
// No kernel includes it and nothing else builds with it.
//
// Oclgrind 21.10 (Debian 12) evaluates the integer overloads min(gentype, sgentype),
// max(gentype, sgentype) and clamp(gentype, sgentype, sgentype) as if the scalar were a vector:
// lane i of the result uses "lane i" of the scalar, read from past the scalar's storage (its
// WorkItemBuiltins.cpp s2arg/s3arg/u2arg/u3arg; the float overloads check for a scalar, the
// integer ones do not). Lanes 1.. then get garbage, e.g. a clamped index far outside its buffer,
// and Oclgrind reports invalid reads that no device makes (in the lane-wise kernels: every
// `min(x, width - 1)` on an intV). Definitions of these overloads here, which broadcast the
// scalar, replace Oclgrind's built-in ones (it only interprets functions the program does not
// define). Oclgrind's other known mis-evaluations, of lane masks that the optimiser turns into i1
// logic with a constant (`!` of a vector mask: 1 / −2 per lane instead of 0 / −1; an all-true
// constant mask or one comparison broadcast to the lanes: 1; `count -= mask`: 255), cannot be fixed
// from here: kernels avoid those forms (GI_NOT in kernels/common/vector_width.h).
// Oclgrind also cannot execute some clang builtins (OCLGRIND FATAL ERROR "Undefined external
// function: llvm.prefetch.p1i8", "llvm.floor.v16f32"; the kernel is then not found): the macros
// at the end map them to what it can run (a prefetch never faults, so dropping it hides nothing).
#define GI_OCLGRIND_SCALAR_MINMAX(T, N)                                                                 \
  __attribute__((overloadable)) T##N min(T##N a, T b) { return min(a, (T##N)(b)); }                    \
  __attribute__((overloadable)) T##N max(T##N a, T b) { return max(a, (T##N)(b)); }                    \
  __attribute__((overloadable)) T##N clamp(T##N x, T lo, T hi) { return clamp(x, (T##N)(lo), (T##N)(hi)); }
#define GI_OCLGRIND_SCALAR_MINMAX_ALL(T)                                                                \
  GI_OCLGRIND_SCALAR_MINMAX(T, 2)                                                                       \
  GI_OCLGRIND_SCALAR_MINMAX(T, 3)                                                                       \
  GI_OCLGRIND_SCALAR_MINMAX(T, 4)                                                                       \
  GI_OCLGRIND_SCALAR_MINMAX(T, 8)                                                                       \
  GI_OCLGRIND_SCALAR_MINMAX(T, 16)
GI_OCLGRIND_SCALAR_MINMAX_ALL(char)
GI_OCLGRIND_SCALAR_MINMAX_ALL(uchar)
GI_OCLGRIND_SCALAR_MINMAX_ALL(short)
GI_OCLGRIND_SCALAR_MINMAX_ALL(ushort)
GI_OCLGRIND_SCALAR_MINMAX_ALL(int)
GI_OCLGRIND_SCALAR_MINMAX_ALL(uint)
GI_OCLGRIND_SCALAR_MINMAX_ALL(long)
GI_OCLGRIND_SCALAR_MINMAX_ALL(ulong)
#undef GI_OCLGRIND_SCALAR_MINMAX_ALL
#undef GI_OCLGRIND_SCALAR_MINMAX

#define __builtin_prefetch(...) ((void)0)
#define __builtin_elementwise_floor(x) floor(x)
