// One kernel source for CPUs and GPUs (PERFORMANCE_FACTS.md): a work-item handles GI_VW adjacent
// pixels through explicit vector types. GI_VW = 16 on CPU devices (PoCL turns float16 into
// AVX-512 code, while a loop inside a one-pixel work-item stays scalar), 1 on GPUs (one pixel
// per work-item, the GPU way). The host passes GI_VW as a build define.
#pragma once

#ifndef GI_VW
#define GI_VW 1
#endif

#if GI_VW == 16
typedef float16 floatV;
typedef int16 intV;
typedef uint16 uintV;
typedef long16 longV;
typedef ulong16 ulongV;
#define GI_LANES (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
#define convert_floatV convert_float16
#define convert_intV convert_int16
#define convert_longV convert_long16
#define convert_ulongV convert_ulong16
#define as_uintV as_uint16
#define as_floatV as_float16
#define convert_uintV convert_uint16
#define vloadV vload16
#define vstoreV vstore16
#define GI_ANY(m) any(m)
#elif GI_VW == 8
typedef float8 floatV;
typedef int8 intV;
typedef uint8 uintV;
typedef long8 longV;
typedef ulong8 ulongV;
#define GI_LANES (int8)(0, 1, 2, 3, 4, 5, 6, 7)
#define convert_floatV convert_float8
#define convert_intV convert_int8
#define convert_longV convert_long8
#define convert_ulongV convert_ulong8
#define as_uintV as_uint8
#define as_floatV as_float8
#define convert_uintV convert_uint8
#define vloadV vload8
#define vstoreV vstore8
#define GI_ANY(m) any(m)
#elif GI_VW == 1
typedef float floatV;
typedef int intV;
typedef uint uintV;
typedef long longV;
typedef ulong ulongV;
#define GI_LANES 0
#define convert_floatV convert_float
#define convert_intV convert_int
#define convert_longV convert_long
#define convert_ulongV convert_ulong
#define as_uintV as_uint
#define as_floatV as_float
#define convert_uintV convert_uint
#define vloadV(i, p) ((p)[i])
#define vstoreV(v, i, p) ((p)[i] = (v))
#define GI_ANY(m) (m)
#else
#error "GI_VW must be 1, 8 or 16"
#endif
