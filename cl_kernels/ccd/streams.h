#ifndef CSTREAMS_CCD_STREAMS_H
#define CSTREAMS_CCD_STREAMS_H
/* Kernels over every candidate or contact stream of a step at once take up to four of
 * them as (items, count, kind) triples, the unused ones counting 0, and go over their
 * concatenation, one work-item an item: a stream of its own would cost a launch,
 * whatever its work. The host binds the triples in stream_args.hpp.
 *
 *   CS_DEFINE_STREAM_ITEM(uint4)
 *   __kernel void k(CS_FOUR_STREAMS(uint4), ...)
 *   {
 *     uint4 item;
 *     uint vertex_face;
 *     if (cs_stream_item_uint4(get_global_id(0), CS_FOUR_STREAM_ARGS, &item, &vertex_face)) ...
 *   }
 *
 * vertex_face: the stream's items are (vertex, face, ...), else (edge, edge, ...). */
#define CS_STREAM_PARAMS(T, k) __global const T *items##k, const uint n##k, const uint vertex_face##k
#define CS_FOUR_STREAMS(T) \
  CS_STREAM_PARAMS(T, 0), CS_STREAM_PARAMS(T, 1), CS_STREAM_PARAMS(T, 2), CS_STREAM_PARAMS(T, 3)
#define CS_FOUR_STREAM_ARGS \
  items0, n0, vertex_face0, items1, n1, vertex_face1, items2, n2, vertex_face2, items3, n3, vertex_face3

/* cs_stream_item_T: item i of the concatenation and its kind; 0 past its end. */
#define CS_DEFINE_STREAM_ITEM(T)                                                                \
  inline int cs_stream_item_##T(const uint i, CS_FOUR_STREAMS(T), T* item, uint* vertex_face) { \
    if (i < n0) {                                                                               \
      *item = items0[i];                                                                        \
      *vertex_face = vertex_face0;                                                              \
    } else if (i < n0 + n1) {                                                                   \
      *item = items1[i - n0];                                                                   \
      *vertex_face = vertex_face1;                                                              \
    } else if (i < n0 + n1 + n2) {                                                              \
      *item = items2[i - n0 - n1];                                                              \
      *vertex_face = vertex_face2;                                                              \
    } else if (i < n0 + n1 + n2 + n3) {                                                         \
      *item = items3[i - n0 - n1 - n2];                                                         \
      *vertex_face = vertex_face3;                                                              \
    } else {                                                                                    \
      return 0;                                                                                 \
    }                                                                                           \
    return 1;                                                                                   \
  }

#endif
