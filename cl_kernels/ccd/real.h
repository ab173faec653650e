#ifndef CSTREAMS_CCD_REAL_H
#define CSTREAMS_CCD_REAL_H
/* The working precision of a solver: CS_REAL_DOUBLE=1 for double, else float.
 * Error bounds below assume every +, -, * is correctly rounded to nearest (OpenCL
 * requires it for both types) and nothing is fused: no contraction, no fast-math. */
#pragma OPENCL FP_CONTRACT OFF

#if CS_REAL_DOUBLE
#if CS_FP64_AMD
#pragma OPENCL EXTENSION cl_amd_fp64 : enable
#else
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
typedef double real;
typedef double2 real2;
typedef double4 real4;
typedef double8 real8;
/* 2^-52: |x| * CS_EPS is at least one ulp of x. CS_TINY covers results that flushed
 * or underflowed to zero (devices may flush subnormals). */
#define CS_EPS 0x1p-52
#define CS_TINY DBL_MIN
#define CS_REAL_MAX DBL_MAX
#else
typedef float real;
typedef float2 real2;
typedef float4 real4;
typedef float8 real8;
#define CS_EPS 0x1p-23f
#define CS_TINY FLT_MIN
#define CS_REAL_MAX FLT_MAX
#endif

/* One step below / above x that is at least one ulp: the subtraction itself rounds
 * to nearest, so the result stays at least half an ulp below x. The step is a macro,
 * for a real or each lane of a real8 alike. */
#define CS_ROUNDING_STEP(x) (fabs(x) * CS_EPS + CS_TINY)
inline real cs_down(real x) { return x - CS_ROUNDING_STEP(x); }
inline real cs_up(real x) { return x + CS_ROUNDING_STEP(x); }
inline real8 cs_up8(real8 x) { return x + CS_ROUNDING_STEP(x); }

/* x >= 0 as the nearest float no greater: a time reported in float stays no later. */
inline float cs_float_down(const real x)
{
  float f = (float)x;
  if ((real)f > x) f = nextafter(f, 0.0f);
  return f;
}

typedef struct {
  real lo, hi;
} cs_interval;

inline cs_interval cs_iv(real lo, real hi)
{
  cs_interval r;
  r.lo = lo;
  r.hi = hi;
  return r;
}
inline cs_interval cs_iadd(cs_interval a, cs_interval b) { return cs_iv(cs_down(a.lo + b.lo), cs_up(a.hi + b.hi)); }
inline cs_interval cs_isub(cs_interval a, cs_interval b) { return cs_iv(cs_down(a.lo - b.hi), cs_up(a.hi - b.lo)); }
inline cs_interval cs_iscale(cs_interval a, real s)
{
  const real x = a.lo * s, y = a.hi * s;
  return cs_iv(cs_down(fmin(x, y)), cs_up(fmax(x, y)));
}
inline cs_interval cs_imul(cs_interval a, cs_interval b)
{
  const real p0 = a.lo * b.lo, p1 = a.lo * b.hi, p2 = a.hi * b.lo, p3 = a.hi * b.hi;
  return cs_iv(cs_down(fmin(fmin(p0, p1), fmin(p2, p3))), cs_up(fmax(fmax(p0, p1), fmax(p2, p3))));
}

#endif
