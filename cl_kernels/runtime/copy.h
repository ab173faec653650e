#ifndef CSTREAMS_RUNTIME_COPY_H
#define CSTREAMS_RUNTIME_COPY_H
/* Items are copied as `words` 32-bit words, so one kernel serves every element type.
 * Items of two and four words (pairs, contacts) move as one vector: word by word, each
 * load of a warp spans twice or four times the bytes it uses. */
inline void cs_copy_item(__global const uint* src, size_t from, __global uint* dst, size_t to, uint words)
{
  if (words == 2u) {
    ((__global uint2*)dst)[to] = ((__global const uint2*)src)[from];
  } else if (words == 4u) {
    ((__global uint4*)dst)[to] = ((__global const uint4*)src)[from];
  } else {
    for (uint w = 0; w < words; ++w) dst[to * words + w] = src[from * words + w];
  }
}

#endif
