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

/* Items from[u] to to[u], u < 2, those with to[u] >= capacity left out: both loads are
 * issued before either store. A work-item with one load in flight at a time left the
 * segment merges (compact.cl) at about 2 TB/s on the H100; two at once took a
 * cloth-ball step's merges from 161 to 140 us. */
inline void cs_copy_two_items(__global const uint* src, const uint from[2], __global uint* dst, const uint to[2],
                              const uint capacity, const uint words)
{
  if (words == 2u) {
    uint2 v[2];
    for (uint u = 0; u < 2u; ++u)
      if (to[u] < capacity) v[u] = ((__global const uint2*)src)[from[u]];
    for (uint u = 0; u < 2u; ++u)
      if (to[u] < capacity) ((__global uint2*)dst)[to[u]] = v[u];
  } else if (words == 4u) {
    uint4 v[2];
    for (uint u = 0; u < 2u; ++u)
      if (to[u] < capacity) v[u] = ((__global const uint4*)src)[from[u]];
    for (uint u = 0; u < 2u; ++u)
      if (to[u] < capacity) ((__global uint4*)dst)[to[u]] = v[u];
  } else {
    for (uint u = 0; u < 2u; ++u)
      if (to[u] < capacity) cs_copy_item(src, from[u], dst, to[u], words);
  }
}

#endif
