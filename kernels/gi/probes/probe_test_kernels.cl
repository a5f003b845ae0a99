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
