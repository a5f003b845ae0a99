// Used only by tests/probes_test.cpp: the device octahedral mapping of probe_field.h on arrays.
#include "gi/probes/probe_field.h"

// Per direction: (encoded x, encoded y, 0, 0) and the decoded round trip.
kernel void probe_oct_round_trip(global const float4* dirs, global float4* encoded, global float4* decoded, int n) {
  int i = get_global_id(0);
  if (i >= n) return;
  float2 o = probe_oct_encode(dirs[i].xyz);
  encoded[i] = (float4)(o, 0.0f, 0.0f);
  decoded[i] = (float4)(probe_oct_decode(o), 0.0f);
}

// The scalar probe_field_irradiance() (what probe rays use) at every pixel of a G-buffer, as
// probe_shade writes it with down = 1: the reference for the lane-wise shading kernel.
kernel void probe_shade_scalar(GiProbeGrid grid, global const float4* irradiance, global const float2* distance,
                               global const float4* probeStates, GiView camera, global const float4* gPosition,
                               global const float4* gGeoNormal, global const float4* gNormal, global const float4* gAlbedo, global float4* out) {
  int px = get_global_id(0), py = get_global_id(1);
  if (px >= camera.width || py >= camera.height) return;
  size_t i = (size_t)py * camera.width + px;
  float4 p = gPosition[i];
  float3 wo = normalize(vload3(0, camera.eye) - p.xyz);
  float3 E = probe_field_irradiance(&grid, irradiance, distance, probeStates, p.xyz, gNormal[i].xyz,
                                    gGeoNormal[i].xyz, wo);
  out[i] = p.w != 0.0f ? (float4)(gAlbedo[i].xyz * GI_INV_PI * E, 0.0f) : (float4)(0.0f);
}
