#ifndef CSTREAMS_CCD_REFINE_STATE_H
#define CSTREAMS_CCD_REFINE_STATE_H
/* What refine.cl's work list holds: its items (a query's box) and each query's state,
 * with the keys its earliest contact is kept in. */
#include "trilinear.h"

#define CS_FLAG_SLACK 1u
#define CS_FLAG_LIMIT 2u
#define CS_FLAG_VERTEX_FACE 4u
#define CS_FLAG_NOT_EARLIEST 8u /* given up: it cannot hold an object's earliest time */
/* A time as the bits of a float no later (cs_float_key_down) or no earlier than it. */
inline uint cs_float_key_down(const real t) { return as_uint(cs_float_down(t)); }

inline uint cs_float_key_up(const real t)
{
  float f = (float)t;
  if ((real)f < t) f = nextafter(f, 2.0f);
  return as_uint(f);
}

/* Each query's earliest contact so far is a key updated by atomic minimum. Times are
 * never negative, so their bits order as they do. In double precision the key is the
 * double where the device has 64-bit atomics; elsewhere (an HD 5870) it is the time
 * rounded down to float. Pruning with that rounded-down time only drops boxes that
 * start after it, so the answer is still no later than any contact: it is the earliest
 * contact the 64-bit key would give, rounded down to float.
 * cs_key_lower(p, seen, k) lowers *p to k, given a value `seen` that *p held before:
 * keys only fall, so where k is no lower than that, there is nothing to do. */
#if CS_REAL_DOUBLE && CS_HAS_INT64_ATOMICS
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
typedef ulong cs_key;
inline cs_key cs_key_of(const real t) { return as_ulong(t); }
inline real cs_time_of(const cs_key k) { return as_double(k); }
inline void cs_key_lower(volatile __global cs_key* p, cs_key seen, const cs_key k)
{
  while (k < seen) {
    const cs_key old = atom_cmpxchg(p, seen, k);
    if (old == seen) break;
    seen = old;
  }
}
#else
typedef uint cs_key;
inline cs_key cs_key_of(const real t) { return cs_float_key_down(t); }
inline real cs_time_of(const cs_key k) { return (real)as_float(k); }
inline void cs_key_lower(volatile __global cs_key* p, const cs_key seen, const cs_key k)
{
  if (k < seen) atomic_min(p, k);
}
#endif

/* 8 + 6 reals bytes (host: add_refine_pass). */
typedef struct {
  uint query, work;
  cs_box box;
} cs_item;

/* 2 keys + 32 bytes, at most 2 reals + 32, 4 more with CS_ESCALATE, and with
 * CS_KEEP_FUNCTION 37 reals more (host: add_refine_pass). The seed looks up the
 * query's vertices once: a round's visit of a box is a chain of dependent reads, one
 * link shorter without the face's or the edges' indices.
 * CS_KEEP_FUNCTION (set where the device is a CPU): the seed also makes the query's
 * function and scale once, and rounds read them instead of making them again from the
 * points for every box: pocl's cloth-ball refinement 1,155 -> 879 ms. Not on a GPU,
 * where reading 148 or 296 bytes a box costs more than making them (H100: cloth-ball's
 * refinement 1.58 -> 1.89 ms, n-body's 0.85 -> 1.86) and the state would hold 75 MB
 * more on cloth-ball. */
typedef struct {
  cs_key best[2];
  uint work[3];
  uint flags;
  uint vertices[4];
#if CS_ESCALATE
  uint proven_end; /* the earliest end of a box a hit proved a zero in, as a float rounded up */
#endif
#if CS_KEEP_FUNCTION
  cs_trilinear f;
  real scale;
#endif
} cs_refine_state;

#define CS_NO_TIME 0x40000000u /* 2.0f: later than any time of a step */

#endif
