#pragma once
/// The 8-wide SIMD vocabulary, pinned to AVX2+FMA. xsimd's default batch is 16 lanes under
/// AVX-512, so every 8-wide type names its architecture explicitly.

#include <xsimd/xsimd.hpp>

namespace rp::simd {

using Arch = xsimd::fma3<xsimd::avx2>;
using float8 = xsimd::batch<float, Arch>;
using int8 = xsimd::batch<int32_t, Arch>;
using mask8 = xsimd::batch_bool<float, Arch>;

static_assert(float8::size == 8, "raypack's packets are 8 rays wide");
static_assert(int8::size == 8, "raypack's packets are 8 rays wide");

}  // namespace rp::simd
