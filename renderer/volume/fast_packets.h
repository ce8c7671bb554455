// The fast kernel's sampling of a run of samples (private to fast_kernel.cpp, included
// inside its per-ISA namespace after fast_shade.h, like it): AVX2 packets of 8 samples
// classified by table and composited in order, or the portable one-sample-at-a-time version
// of the same arithmetic.
#pragma once

#ifdef TESSERA_AVX2
// Permutations that move the lanes set in an 8-bit mask to the front (AVX2 has no
// compress instruction): entry m lists the set lanes of m in order.
struct CompressTable {
  alignas(8) uint8_t lanes[256][8];
  constexpr CompressTable() : lanes{} {
    for (int m = 0; m < 256; ++m) {
      int n = 0;
      for (int l = 0; l < 8; ++l)
        if (m & (1 << l)) lanes[m][n++] = (uint8_t)l;
    }
  }
};
constexpr CompressTable kCompress;

// Classified samples of a chunk, in ray order: table index, interpolation weight and the
// sample's offset in the chunk; only samples that may have alpha > 0 are listed.
struct Classified {
  // Samples per chunk (a multiple of kLanes). Opaque rays end a few samples in, and a chunk is
  // classified whole first: 32 rather than 64 made an opaque Marschner-Lobb frame ~15% faster
  // at an unchanged hollow-shell time; 16 cost the shell (AMD EPYC, AVX2, 1024^2, 2 threads).
  static constexpr int kChunk = 32;
  alignas(32) int32_t ti[kChunk + kLanes];
  alignas(32) float w[kChunk + kLanes];
  alignas(32) int32_t off[kChunk + kLanes];
};

// Samples k0..k0+lanes-1 and appends those that may have alpha > 0 to `out` at position n
// (`first_off`: offset of k0 in the chunk). Returns how many were appended. No branches on
// the data, so consecutive packets overlap in the pipeline.
// kEarlyOutEmpty: return early for an all-empty packet. That branch pays where it is predictable
// (long runs without skipping: most packets are empty) and costs where it is a coin flip
// (short runs between leaps).
// kOcc: first test the samples' cells (c.occ, one gather) and return before fetching any
// voxel if none can be non-empty; lanes in empty cells are not listed.
template <bool kEarlyOutEmpty, bool kOcc>
inline int classifyPacket(const Consts& c, int64_t k0, int lanes, int first_off, Classified& out, int n) {
  const __m256 kf = _mm256_add_ps(_mm256_set1_ps((float)k0), _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7));
  __m256 f[3];
  __m256i i[3];
  for (int a = 0; a < 3; ++a) {
    __m256 u = _mm256_fmadd_ps(kf, _mm256_set1_ps(c.du[a]), _mm256_set1_ps(c.u0[a]));
    u = _mm256_min_ps(_mm256_max_ps(u, _mm256_setzero_ps()), _mm256_set1_ps(c.umax[a]));
    i[a] = _mm256_min_epi32(_mm256_cvttps_epi32(u), _mm256_set1_epi32(c.imax[a]));
    f[a] = _mm256_sub_ps(u, _mm256_cvtepi32_ps(i[a]));
  }
  // Brick of the lower corner and position inside it; all eight corners are in that brick.
  constexpr int sh = std::countr_zero((unsigned)MinMaxHierarchy::kBlock);  // kBlock is a power of two
  const __m256i seven = _mm256_set1_epi32(MinMaxHierarchy::kBlock - 1);
  const __m256i brick = _mm256_add_epi32(
      _mm256_srli_epi32(i[0], sh),
      _mm256_add_epi32(_mm256_mullo_epi32(_mm256_srli_epi32(i[1], sh), _mm256_set1_epi32(c.nb_x)),
                       _mm256_mullo_epi32(_mm256_srli_epi32(i[2], sh), _mm256_set1_epi32(c.nb_xy))));
  const __m256i local = _mm256_add_epi32(
      _mm256_and_si256(i[0], seven),
      _mm256_add_epi32(_mm256_mullo_epi32(_mm256_and_si256(i[1], seven), _mm256_set1_epi32(VolumeAccel::kEdge)),
                       _mm256_mullo_epi32(_mm256_and_si256(i[2], seven),
                                          _mm256_set1_epi32(VolumeAccel::kEdge * VolumeAccel::kEdge))));
  int occupied = (1 << lanes) - 1;
  if constexpr (kOcc) {
    // Bit x + 8 y + 64 z (cellBit, the cell's place in its brick) of the brick's 512, read as
    // sixteen 32-bit words.
    const __m256i cell = _mm256_or_si256(
        _mm256_and_si256(i[0], seven),
        _mm256_or_si256(_mm256_slli_epi32(_mm256_and_si256(i[1], seven), 3), _mm256_slli_epi32(_mm256_and_si256(i[2], seven), 6)));
    const __m256i word = _mm256_add_epi32(_mm256_slli_epi32(brick, 4), _mm256_srli_epi32(cell, 5));
    const __m256i w = _mm256_i32gather_epi32(reinterpret_cast<const int*>(c.occ), word, 4);
    const __m256i on = _mm256_and_si256(_mm256_srlv_epi32(w, _mm256_and_si256(cell, _mm256_set1_epi32(31))),
                                        _mm256_set1_epi32(1));
    occupied &= _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(on, _mm256_set1_epi32(1))));
    if (occupied == 0) return 0;
  }
  const __m256i idx = _mm256_add_epi32(_mm256_mullo_epi32(brick, _mm256_set1_epi32(VolumeAccel::kBrickSize)), local);
  // The eight corners as four x pairs, each a 32-bit read of two uint16 voxels per lane: by
  // gather instructions or one lane at a time, as suits the CPU (common/cpu.h, cpuGathers). On
  // AMD Zen 4 (1024^2, 2 threads) the lane reads took 0.95-0.96x the time of a frame with the
  // AVX-512 kernel and 0.93-0.99x with the AVX2 kernel; on an Intel Xeon the gathers were faster.
  // The choice is the same for every packet of a frame: a branch the CPU predicts.
  constexpr int oy = VolumeAccel::kEdge, oz = VolumeAccel::kEdge * VolumeAccel::kEdge;
  __m256i g00, g10, g01, g11;
  if (c.gather) {
    auto gather = [&](const uint16_t* base) {
      return _mm256_i32gather_epi32(reinterpret_cast<const int*>(base), idx, sizeof(uint16_t));
    };
    g00 = gather(c.vol), g10 = gather(c.vol + oy), g01 = gather(c.vol + oz), g11 = gather(c.vol + oy + oz);
  } else {
    alignas(32) int32_t id[kLanes];
    _mm256_store_si256(reinterpret_cast<__m256i*>(id), idx);
    auto oneByOne = [&](const uint16_t* base) {
      auto at = [&](int l) {
        int32_t v;
        std::memcpy(&v, base + id[l], 4);
        return v;
      };
      __m128i lo = _mm_cvtsi32_si128(at(0)), hi = _mm_cvtsi32_si128(at(4));
      lo = _mm_insert_epi32(lo, at(1), 1), hi = _mm_insert_epi32(hi, at(5), 1);
      lo = _mm_insert_epi32(lo, at(2), 2), hi = _mm_insert_epi32(hi, at(6), 2);
      lo = _mm_insert_epi32(lo, at(3), 3), hi = _mm_insert_epi32(hi, at(7), 3);
      return _mm256_set_m128i(hi, lo);
    };
    g00 = oneByOne(c.vol), g10 = oneByOne(c.vol + oy), g01 = oneByOne(c.vol + oz), g11 = oneByOne(c.vol + oy + oz);
  }
  const __m256i low = _mm256_set1_epi32(0xFFFF);
  auto lerpx = [&](__m256i g) {
    const __m256 v0 = _mm256_cvtepi32_ps(_mm256_and_si256(g, low));
    const __m256 v1 = _mm256_cvtepi32_ps(_mm256_srli_epi32(g, 16));
    return _mm256_fmadd_ps(f[0], _mm256_sub_ps(v1, v0), v0);
  };
  auto lerp = [](__m256 a, __m256 b2, __m256 t) { return _mm256_fmadd_ps(t, _mm256_sub_ps(b2, a), a); };
  const __m256 s = lerp(lerp(lerpx(g00), lerpx(g10), f[1]), lerp(lerpx(g01), lerpx(g11), f[1]), f[2]);
  __m256 ft = _mm256_fmadd_ps(s, _mm256_set1_ps(c.to_table), _mm256_set1_ps(c.table_offset));
  ft = _mm256_min_ps(_mm256_max_ps(ft, _mm256_setzero_ps()), _mm256_set1_ps((float)(TfTable::kEntries - 1)));
  const __m256i ti = _mm256_min_epi32(_mm256_cvttps_epi32(ft), _mm256_set1_epi32(TfTable::kEntries - 2));
  const __m256 w = _mm256_sub_ps(ft, _mm256_cvtepi32_ps(ti));
  // Range filter instead of a gather of c.nonzero: lanes outside [first, last] have
  // exactly zero alpha; lanes inside with zero alpha composite as exact no-ops.
  const __m256i out_of_range = _mm256_or_si256(_mm256_cmpgt_epi32(_mm256_set1_epi32(c.first_nz), ti),
                                               _mm256_cmpgt_epi32(ti, _mm256_set1_epi32(c.last_nz)));
  int mask = ~_mm256_movemask_ps(_mm256_castsi256_ps(out_of_range));
  mask &= occupied;
  if (kEarlyOutEmpty && mask == 0) return 0;
  const __m256i perm = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(kCompress.lanes[mask])));
  const __m256i off = _mm256_add_epi32(_mm256_set1_epi32(first_off), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.ti + n), _mm256_permutevar8x32_epi32(ti, perm));
  _mm256_storeu_ps(out.w + n, _mm256_permutevar8x32_ps(w, perm));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.off + n), _mm256_permutevar8x32_epi32(off, perm));
  return __builtin_popcount((unsigned)mask);
}

// Samples [begin, end) composited front to back into acc, in chunks: all packets of a
// chunk are classified first, then the listed samples composited in order (the same
// operations, in the same order, as one sample at a time). Returns true if the alpha
// reached et; `stop` is the sample after the last one used.
// kShade: c.grad is set (a loop of its own: the unlit loop stays short).
template <bool kEarlyOutEmpty, bool kOcc, bool kShade>
[[gnu::always_inline]] inline bool runPackets(const Consts& c, int64_t begin, int64_t end, float et, Accum& out, int64_t& stop) {
  // Locals: `out` may alias the table's floats as far as the compiler knows, so compositing
  // into it stored and reloaded it for every sample (a longer dependency chain).
  __m128 acc = out.c, trans = out.t;
  Classified cl;
  const __m128 etv = _mm_set1_ps(et);
  for (int64_t j = begin; j < end; j += Classified::kChunk) {
    const int64_t chunk_end = std::min(end, j + Classified::kChunk);
    int n = 0;
    for (int64_t p = j; p < chunk_end; p += kLanes)
      n += classifyPacket<kEarlyOutEmpty, kOcc>(c, p, (int)std::min<int64_t>(kLanes, chunk_end - p), (int)(p - j), cl, n);
    if constexpr (kShade) {
      // Lit kLanes samples at a time (shadePacket), then composited one by one. A ray that ends
      // early wastes the lighting of at most kLanes - 1 samples.
      for (int i0 = 0; i0 < n; i0 += kLanes) {
        const int m = std::min(kLanes, n - i0);
        __m128 pc[kLanes];
        for (int l = 0; l < kLanes; ++l) {
          const int i = i0 + (l < m ? l : 0);  // idle lanes repeat the first sample
          const float* e = c.rgba + 4 * cl.ti[i];
          const __m128 e0 = _mm_load_ps(e), e1 = _mm_load_ps(e + 4);
          pc[l] = _mm_fmadd_ps(_mm_set1_ps(cl.w[i]), _mm_sub_ps(e1, e0), e0);
        }
        // Offsets of the m listed samples (the rest of the array is unwritten: not read).
        const __m256i used = _mm256_cmpgt_epi32(_mm256_set1_epi32(m), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
        const __m256i offs = _mm256_blendv_epi8(_mm256_set1_epi32(cl.off[i0]),
                                                _mm256_maskload_epi32(cl.off + i0, used), used);
        const __m256 kf = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32((int)j), offs));
        // Eight (r, g, b, a) to four eight-lane channels and back.
        __m128 a0 = pc[0], a1 = pc[1], a2 = pc[2], a3 = pc[3], b0 = pc[4], b1 = pc[5], b2 = pc[6], b3 = pc[7];
        _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
        _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
        __m256 soa[4] = {_mm256_set_m128(b0, a0), _mm256_set_m128(b1, a1), _mm256_set_m128(b2, a2),
                         _mm256_set_m128(b3, a3)};
        shadePacket(c, kf, soa);
        a0 = _mm256_castps256_ps128(soa[0]), a1 = _mm256_castps256_ps128(soa[1]);
        a2 = _mm256_castps256_ps128(soa[2]), a3 = _mm256_castps256_ps128(soa[3]);
        b0 = _mm256_extractf128_ps(soa[0], 1), b1 = _mm256_extractf128_ps(soa[1], 1);
        b2 = _mm256_extractf128_ps(soa[2], 1), b3 = _mm256_extractf128_ps(soa[3], 1);
        _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
        _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
        const __m128 lit[kLanes] = {a0, a1, a2, a3, b0, b1, b2, b3};
        for (int l = 0; l < m; ++l) {
          acc = _mm_fmadd_ps(trans, lit[l], acc);
          trans = _mm_fnmadd_ps(trans, _mm_shuffle_ps(lit[l], lit[l], 0xFF), trans);
          if (_mm_movemask_ps(_mm_cmpge_ps(acc, etv)) & 8) {
            out = Accum{acc, trans};
            stop = j + cl.off[i0 + l] + 1;
            return true;
          }
        }
      }
      continue;
    }
    for (int i = 0; i < n; ++i) {
      const float* e = c.rgba + 4 * cl.ti[i];
      const __m128 e0 = _mm_load_ps(e), e1 = _mm_load_ps(e + 4);
      const __m128 pc = _mm_fmadd_ps(_mm_set1_ps(cl.w[i]), _mm_sub_ps(e1, e0), e0);
      acc = _mm_fmadd_ps(trans, pc, acc);
      trans = _mm_fnmadd_ps(trans, _mm_shuffle_ps(pc, pc, 0xFF), trans);  // trans - trans * alpha, one rounding
      if (_mm_movemask_ps(_mm_cmpge_ps(acc, etv)) & 8) {
        out = Accum{acc, trans};
        stop = j + cl.off[i] + 1;
        return true;
      }
    }
  }
  out = Accum{acc, trans};
  stop = end;
  return false;
}
#else
// Portable version of the same arithmetic (one sample at a time).
inline int packet(const Consts& c, int64_t k0, int lanes, float et, Accum& acc, bool& done) {
  auto lerp = [](float a, float b, float t) { return std::fma(t, b - a, a); };
  for (int l = 0; l < lanes; ++l) {
    float f[3];
    int i[3];
    samplePosition(c, k0 + l, i, f);
    constexpr int B = MinMaxHierarchy::kBlock;
    const size_t brick = (size_t)(i[0] / B) + (size_t)(i[1] / B) * c.nb_x + (size_t)(i[2] / B) * c.nb_xy;
    // An empty cell (cellBit; not called: an inline function shared between the ISAs' copies).
    const int cell = (i[0] & 7) | (i[1] & 7) << 3 | (i[2] & 7) << 6;
    if (c.occ && !((c.occ[brick * 8 + cell / 64] >> (cell % 64)) & 1)) continue;
    const uint16_t* p = c.vol + brick * VolumeAccel::kBrickSize + (i[0] % B) +
                        VolumeAccel::kEdge * ((i[1] % B) + VolumeAccel::kEdge * (i[2] % B));
    constexpr int oy = VolumeAccel::kEdge, oz = VolumeAccel::kEdge * VolumeAccel::kEdge;
    auto lx = [&](const uint16_t* q) { return lerp((float)q[0], (float)q[1], f[0]); };
    const float s = lerp(lerp(lx(p), lx(p + oy), f[1]), lerp(lx(p + oz), lx(p + oy + oz), f[1]), f[2]);
    const float ft = std::min(std::max(std::fma(s, c.to_table, c.table_offset), 0.0f), (float)(TfTable::kEntries - 1));
    const int ti = std::min((int)ft, TfTable::kEntries - 2);
    const float w = ft - (float)ti;
    if (!c.nonzero[ti]) continue;
    float pc[4];
    for (int ch = 0; ch < 4; ++ch) pc[ch] = lerp(c.rgba[4 * ti + ch], c.rgba[4 * ti + 4 + ch], w);
    if (c.grad) shadeSample(c, k0 + l, pc);
    for (int ch = 0; ch < 4; ++ch) acc.c[ch] = std::fma(acc.t, pc[ch], acc.c[ch]);
    acc.t = std::fma(-acc.t, pc[3], acc.t);
    if (acc.c[3] >= et) {
      done = true;
      return l + 1;
    }
  }
  return lanes;
}
#endif
