/* tsf_runtime.c: the C99 runtime of the controllers tsfc generates (see
 * tsf_runtime.h). Compile it once per image, with the flags of the generated
 * files.
 *
 * Each function is written once over a real type TSF_R and instantiated for
 * double and for float: the second half of this file is included twice by the
 * first (with TSF_RUNTIME_INSTANCE defined), so keep the file name. Every
 * operation is the Rust runtime's, in its order, one product per statement.
 */

#ifndef TSF_RUNTIME_INSTANCE

#include "tsf_runtime.h"

#include <math.h>
#include <string.h>

/* ------------------------------------------------- binary64 arc tangent */

/* tsf-runtime's math::atan, operation by operation (binary64). */

/* (atan(j/16) high, low), j = 0..39. */
static const double tsf_atan_j16[40][2] = {
    {0.0, 0.0},
    {0.06241880999595735, -1.5490756308295046e-18},
    {0.12435499454676144, -3.1253241424539383e-18},
    {0.18534794999569476, 4.180692268843079e-18},
    {0.24497866312686414, 1.0698755618734451e-17},
    {0.3028848683749714, -1.1010827903001369e-17},
    {0.35877067027057225, -2.4623815582638635e-17},
    {0.4124104415973873, -1.587652227770689e-17},
    {0.4636476090008061, 2.2698777452961687e-17},
    {0.5123894603107377, -2.5462781472855804e-17},
    {0.5585993153435624, -5.4556305485916264e-18},
    {0.6022873461349642, 2.950430737228402e-17},
    {0.6435011087932844, 1.5834785051444286e-17},
    {0.6823165548747481, 6.943223671560008e-18},
    {0.7188299996216245, -2.1478388444456983e-17},
    {0.7531512809621944, -2.4256934659182068e-17},
    {0.7853981633974483, 3.061616997868383e-17},
    {0.8156919233162234, -1.071456562778743e-17},
    {0.844153986113171, -4.841337011934917e-17},
    {0.870903457075653, -2.269823590747287e-17},
    {0.8960553845713439, 2.923876285774305e-17},
    {0.9197196053504169, -4.057439412852768e-17},
    {0.9420000403794636, 5.4608374858466876e-17},
    {0.9629943306809362, -3.9866605952107524e-18},
    {0.982793723247329, 1.3903311031230998e-17},
    {1.0014831356942346, 9.438308023545392e-17},
    {1.0191413442663497, 1.0004018869366799e-17},
    {1.0358412530088001, 3.194313981784504e-17},
    {1.0516502125483738, -9.650564731467514e-17},
    {1.0666303653157436, -5.956589637160375e-17},
    {1.0808390005411683, -1.5676322511359073e-17},
    {1.09432890732119, -5.490676155022364e-18},
    {1.1071487177940904, 9.40447137356638e-17},
    {1.1193432352423422, 6.954284199374601e-17},
    {1.1309537439791604, 7.123833804538446e-17},
    {1.1420182993488803, -9.642430524429942e-17},
    {1.1525719972156676, -9.159738508900379e-17},
    {1.1626472230398073, 6.255046986097143e-17},
    {1.1722738811284763, 8.385188614028674e-17},
    {1.1814796049617557, 1.511867738554561e-17}
};

/* (pi/2 - atan(j/16)) high, low, j = 0..7. */
static const double tsf_atan_comp_j16[8][2] = {
    {1.5707963267948966, 6.123233995736766e-17},
    {1.5083775167989393, -6.6075234508751206e-18},
    {1.446441332248135, 9.211323971545052e-17},
    {1.3854483767992019, 1.540496457266753e-18},
    {1.3258176636680326, -8.824429373951136e-17},
    {1.2679114584199251, 7.224316786036903e-17},
    {1.2120256565243244, 3.034500430874847e-17},
    {1.1583858851975093, 2.1597711003816724e-17}
};

/* Taylor coefficients of atan(t)/t - 1 = s Q(s), s = t^2: -1/3, 1/5, ..., -1/23. */
static const double tsf_atan_q[11] = {
    -0.3333333333333333,
    0.2,
    -0.14285714285714285,
    0.1111111111111111,
    -0.09090909090909091,
    0.07692307692307693,
    -0.06666666666666667,
    0.058823529411764705,
    -0.05263157894736842,
    0.047619047619047616,
    -0.043478260869565216
};

/* atan(t) - t for |t| <= 1/8: t (s Q(s)), Horner innermost first. */
static double tsf_atan_tail(double t) {
    const double s = t * t;
    double acc = 0.0;
    int k;
    for (k = 10; k >= 0; k--) {
        const double m = s * acc;
        acc = tsf_atan_q[k] + m;
    }
    {
        const double sq = s * acc;
        return t * sq;
    }
}

/* Arc tangent on a = |x| (sign restored at the end): a < 2^-27 -> x;
   a > 2^66 -> pi/2; a < 1/8 -> a + tail(a); a <= 39/16 -> j = trunc(16a + 1/2),
   c = j/16, t = (a - c)/(1 + a c), atan(j/16) + t + tail(t); else
   j = trunc(16/a + 1/2), t = (1 - a c)/(a + c), pi/2 - atan(j/16) - (t + tail(t)). */
static double tsf_atan_f64(double x) {
    double a;
    double r;
    if (isnan(x) != 0) {
        return x;
    }
    a = fabs(x);
    if (a < 7.450580596923828e-09) {
        return x;
    }
    if (a > 7.378697629483821e19) {
        r = tsf_atan_comp_j16[0][0] + tsf_atan_comp_j16[0][1];
    } else if (a < 0.125) {
        const double tl = tsf_atan_tail(a);
        r = a + tl;
    } else if (a <= 2.4375) {
        const double a16 = a * 16.0;
        const int j = (int)(a16 + 0.5);
        const double c = (double)j * 0.0625;
        const double num = a - c;
        const double ac = a * c;
        const double den = 1.0 + ac;
        const double t = num / den;
        const double tl = tsf_atan_tail(t);
        const double tt = t + tl;
        const double hi = j >= 0 && j < 40 ? tsf_atan_j16[j][0] : 0.0;
        const double lo = j >= 0 && j < 40 ? tsf_atan_j16[j][1] : 0.0;
        const double lt = lo + tt;
        r = hi + lt;
    } else {
        const double q16 = 16.0 / a;
        const int j = (int)(q16 + 0.5);
        const double c = (double)j * 0.0625;
        const double ac = a * c;
        const double num = 1.0 - ac;
        const double den = a + c;
        const double t = num / den;
        const double tl = tsf_atan_tail(t);
        const double tt = t + tl;
        const double hi = j >= 0 && j < 8 ? tsf_atan_comp_j16[j][0] : 0.0;
        const double lo = j >= 0 && j < 8 ? tsf_atan_comp_j16[j][1] : 0.0;
        const double lt = lo - tt;
        r = hi + lt;
    }
    return signbit(x) ? -r : r;
}

/* ------------------------------------------- binary64 exp, sin and cos */

/* tsf-runtime's math::exp, math::sin and math::cos (runtime/src/math/mod.rs),
   operation by operation in binary64, one operation per statement, with the
   runtime's constants as hex floats (the bit patterns of math::SIN_S etc.):
   bit for bit the Rust runtime's results, no libm call. The Payne-Hanek
   reduction's 128-bit integers are pairs of 64-bit words (C99 has no wider
   integer). Bit patterns through memcpy. */

static uint64_t tsf_f64_bits(double v) {
    uint64_t b;
    (void)memcpy(&b, &v, sizeof b);
    return b;
}

static double tsf_f64_from_bits(uint64_t b) {
    double v;
    (void)memcpy(&v, &b, sizeof v);
    return v;
}

/* 2^k for -1022 <= k <= 1023 (k clamped), from the exponent bits. */
static double tsf_pow2(int k) {
    const int c = k < -1022 ? -1022 : (k > 1023 ? 1023 : k);
    const int biased = c + 1023;
    const uint64_t field = (uint64_t)biased;
    return tsf_f64_from_bits(field << 52);
}

/* math::EXP_P: Taylor coefficients of r coth(r/2) - 2, 1/6 ... -691/653837184000. */
static const double tsf_exp_p[6] = {
    0x1.5555555555555p-3,  -0x1.6c16c16c16c17p-9, 0x1.1566abc011567p-14,
    -0x1.bbd779334ef0bp-20, 0x1.66a8f2bf70ebep-25, -0x1.22805d644267fp-30
};

/* e^x: NaN -> NaN, x > EXP_OVERFLOW -> inf, x <= EXP_UNDERFLOW -> 0,
   |x| < 2^-28 -> 1 + x; k = trunc(x/ln2 +- 1/2), hi = x - k LN2_HI,
   lo = k LN2_LO, r = hi - lo, c = r - s P(s) (s = r r, Horner from 0),
   y = 1 - ((lo - r c/(2 - c)) - hi), times 2^k in one or two products. */
double tsf_exp(double x) {
    if (isnan(x) != 0) {
        return x;
    }
    if (x > 0x1.62e42fefa39efp+9) {
        return HUGE_VAL;
    }
    if (x <= -0x1.74910d52d3052p+9) {
        return 0.0;
    }
    if (fabs(x) < 0x1p-28) {
        return 1.0 + x;
    }
    {
        const double half = x < 0.0 ? -0.5 : 0.5;
        const double xl = x * 0x1.71547652b82fep+0;
        const double kr = xl + half;
        const int k = (int)kr;
        const double kf = (double)k;
        const double kh = kf * 0x1.62e42fefa38p-1;
        const double hi = x - kh;
        const double lo = kf * 0x1.ef35793c7673p-45;
        const double r = hi - lo;
        const double s = r * r;
        double p = 0.0;
        int j;
        for (j = 5; j >= 0; j--) {
            const double sp = s * p;
            p = tsf_exp_p[j] + sp;
        }
        {
            const double sp = s * p;
            const double c = r - sp;
            const double rc = r * c;
            const double q = rc / (2.0 - c);
            const double y = 1.0 - ((lo - q) - hi);
            if (k > 1023) {
                const double y2 = y * 2.0;
                return y2 * tsf_pow2(k - 1);
            }
            if (k < -1021) {
                const double ys = y * tsf_pow2(k + 1000);
                return ys * tsf_pow2(-1000);
            }
            return y * tsf_pow2(k);
        }
    }
}

/* 2/pi, 1280 bits, most significant first (math::TWO_OVER_PI); the float
   reduction reads the first four words. */
static const uint64_t tsf_two_over_pi[20] = {
    0xA2F9836E4E441529ull, 0xFC2757D1F534DDC0ull, 0xDB6295993C439041ull, 0xFE5163ABDEBBC561ull,
    0xB7246E3A424DD2E0ull, 0x06492EEA09D1921Cull, 0xFE1DEB1CB129A73Eull, 0xE88235F52EBB4484ull,
    0xE99C7026B45F7E41ull, 0x3991D639835339F4ull, 0x9C845F8BBDF9283Bull, 0x1FF897FFDE05980Full,
    0xEF2F118B5A0A6D1Full, 0x6D367ECF27CB09B7ull, 0x4F463F669E5FEA2Dull, 0x7527BAC7EBE5F17Bull,
    0x3D0739F78A5292EAull, 0x6BFB5FB11F8D5D08ull, 0x56033046FC7B6BABull, 0xF0CFBC209AF4361Dull
};

/* Word k of tsf_two_over_pi, 0 outside the table (k = -1: the integer part). */
static uint64_t tsf_two_over_pi_word(int k) {
    return (k >= 0 && k < 20) ? tsf_two_over_pi[k] : 0u;
}

/* Biased exponent field of x. */
static int tsf_exponent_bits(double x) {
    const uint64_t field = (tsf_f64_bits(x) >> 52) & 0x7ffu;
    return (int)field;
}

/* a b = (*hi 2^64 + *lo) exactly, from 32-bit halves. */
static void tsf_mul_64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo) {
    const uint64_t a0 = a & 0xffffffffu, a1 = a >> 32;
    const uint64_t b0 = b & 0xffffffffu, b1 = b >> 32;
    const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    const uint64_t mid = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu);
    *lo = (mid << 32) | (p00 & 0xffffffffu);
    *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

/* (*hi, *lo) = a b + c, the 128-bit product plus a 64-bit word (no overflow:
   a < 2^53). */
static void tsf_mul_add_64(uint64_t a, uint64_t b, uint64_t c, uint64_t *hi, uint64_t *lo) {
    uint64_t h, l;
    tsf_mul_64(a, b, &h, &l);
    *lo = l + c;
    *hi = h + (*lo < l ? 1u : 0u);
}

/* Leading zeros of the 128-bit (hi, lo), not both 0. */
static int tsf_leading_zeros_128(uint64_t hi, uint64_t lo) {
    uint64_t v = hi;
    int n = 0;
    int step;
    if (hi == 0u) {
        v = lo;
        n = 64;
    }
    for (step = 32; step > 0; step = step / 2) {
        const int keep = 64 - step;
        const unsigned sh = (unsigned)keep;
        if ((v >> sh) == 0u) {
            v = v << (unsigned)step;
            n = n + step;
        }
    }
    return n;
}

/* Veltkamp split: a = *hi + *lo with a 26-bit *hi. */
static void tsf_split(double a, double *hi, double *lo) {
    const double c = 134217729.0 * a;
    const double d = c - a;
    *hi = c - d;
    *lo = a - *hi;
}

/* Dekker: a b = *p + *e exactly, no fused multiply-add. */
static void tsf_two_prod(double a, double b, double *p, double *e) {
    double ah, al, bh, bl;
    *p = a * b;
    tsf_split(a, &ah, &al);
    tsf_split(b, &bh, &bl);
    {
        const double hh = ah * bh;
        const double d1 = hh - *p;
        const double hl = ah * bl;
        const double d2 = d1 + hl;
        const double lh = al * bh;
        const double d3 = d2 + lh;
        const double ll = al * bl;
        *e = d3 + ll;
    }
}

/* The 64 bits of 2/pi that math::rem_pio2_large's word(j) reads: words k + j
   and k + j + 1 shifted by s. */
static uint64_t tsf_two_over_pi_at(int k, unsigned s) {
    const uint64_t a = tsf_two_over_pi_word(k);
    if (s == 0u) {
        return a;
    }
    return (a << s) | (tsf_two_over_pi_word(k + 1) >> (64u - s));
}

/* |f| (the 128-bit fraction (mh, ml), not 0) times pi/2 as y0 + y1: the top
   64 normalised bits a, the next 64 b, hi = a, lo = (a - hi) 2^64 + b,
   scaled, then the Dekker product with PIO2_HI + PIO2_LO. */
static void tsf_fraction_pio2(uint64_t mh, uint64_t ml, double *y0, double *y1) {
    const int lz = tsf_leading_zeros_128(mh, ml);
    uint64_t a, b;
    if (lz >= 64) {
        const int over = lz - 64;
        a = ml << (unsigned)over;
        b = 0u;
    } else if (lz == 0) {
        a = mh;
        b = ml;
    } else {
        const int rest = 64 - lz;
        a = (mh << (unsigned)lz) | (ml >> (unsigned)rest);
        b = ml << (unsigned)lz;
    }
    {
        const double hi = (double)a;
        /* a - hi, exact and below 2^11 in magnitude; hi may be 2^64. */
        const uint64_t hu = hi >= 0x1p64 ? 0u : (uint64_t)hi;
        const uint64_t du = a - hu;
        const uint64_t nd = 0u - du;
        const double d = (du >> 63) != 0u ? -(double)nd : (double)du;
        const double dw = d * 0x1p64;
        const double bd = (double)b;
        const double lo = dw + bd;
        const double fh = hi * tsf_pow2(-64 - lz);
        const double fl = lo * tsf_pow2(-128 - lz);
        double ph, pe;
        tsf_two_prod(fh, 0x1.921fb54442d18p+0, &ph, &pe);
        {
            const double t1 = fh * 0x1.1a62633145c07p-54;
            const double t2 = fl * 0x1.921fb54442d18p+0;
            const double t3 = t1 + t2;
            const double tail = pe + t3;
            const double s = ph + tail;
            const double back = s - ph;
            *y0 = s;
            *y1 = tail - back;
        }
    }
}

/* math::rem_pio2_large: Payne-Hanek for finite |x| >= 2^20 pi/2. |x| = m 2^e;
   the 192 bits W of 2/pi from bit e - 2 on, P = m W in 64-bit limbs; the
   quadrant is bits 190-191, the top 128 of the 190 fraction bits are rounded
   to the nearest quadrant and multiplied by pi/2. Returns n, writes y0, y1. */
static int tsf_rem_pio2_large(double x, double *y0, double *y1) {
    const uint64_t bits = tsf_f64_bits(x);
    const int e = tsf_exponent_bits(x) - 1075;
    const uint64_t m = (bits & 0x000fffffffffffffull) | 0x0010000000000000ull;
    const int q = e - 2;
    const int k = q >= 0 ? q / 64 : -((63 - q) / 64);
    const int shift = q - (64 * k);
    const unsigned s = (unsigned)shift;
    uint64_t p2h, p2l, p1h, p1l, p0h, p0l;
    uint64_t fh, fl;
    int n, neg = 0;
    double v0 = 0.0, v1 = 0.0;
    tsf_mul_64(m, tsf_two_over_pi_at(k + 2, s), &p2h, &p2l);
    tsf_mul_add_64(m, tsf_two_over_pi_at(k + 1, s), p2h, &p1h, &p1l);
    tsf_mul_add_64(m, tsf_two_over_pi_at(k, s), p1h, &p0h, &p0l);
    (void)p0h;
    n = (int)(p0l >> 62);
    fh = ((p0l & 0x3fffffffffffffffull) << 2) | (p1l >> 62);
    fl = (p1l << 2) | (p2l >> 62);
    if ((fh >> 63) != 0u) {
        n = n + 1;
        neg = 1;
        fl = (~fl) + 1u;
        fh = (~fh) + (fl == 0u ? 1u : 0u);
    }
    if (fh != 0u || fl != 0u) {
        tsf_fraction_pio2(fh, fl, &v0, &v1);
        if (neg != 0) {
            v0 = -v0;
            v1 = -v1;
        }
    }
    if (x < 0.0) {
        *y0 = -v0;
        *y1 = -v1;
        return -n;
    }
    *y0 = v0;
    *y1 = v1;
    return n;
}

/* math::rem_pio2: x = n pi/2 + (y0 + y1) for finite |x| > pi/4. Cody-Waite
   below 2^20 pi/2 (fdlibm's three-step split of pi/2, each step only when
   more bits cancelled), Payne-Hanek above. Returns n, writes y0, y1. */
static int tsf_rem_pio2(double x, double *y0, double *y1) {
    if (fabs(x) >= 0x1.921fb54ebfd3ap+20) {
        return tsf_rem_pio2_large(x, y0, y1);
    }
    {
        const double half = x < 0.0 ? -0.5 : 0.5;
        const double xn = x * 0x1.45f306dc9c883p-1;
        const double nr = xn + half;
        const int n = (int)nr;
        const double fn = (double)n;
        const int j = tsf_exponent_bits(x);
        const double n1 = fn * 0x1.921fb544p+0;
        double r = x - n1;
        double w = fn * 0x1.0b4611a626331p-34;
        double y = r - w;
        if (j - tsf_exponent_bits(y) > 16) {
            double t = r;
            const double n2t = fn * 0x1.3198a2e037073p-69;
            w = fn * 0x1.0b4611a6p-34;
            r = t - w;
            w = n2t - ((t - r) - w);
            y = r - w;
            if (j - tsf_exponent_bits(y) > 49) {
                const double n3t = fn * 0x1.b839a252049c1p-104;
                t = r;
                w = fn * 0x1.3198a2ep-69;
                r = t - w;
                w = n3t - ((t - r) - w);
                y = r - w;
            }
        }
        *y0 = y;
        *y1 = (r - y) - w;
        return n;
    }
}

/* sin(x + y), |x + y| <= ~pi/4 (fdlibm/musl __sin, math::kernel_sin). */
static double tsf_kernel_sin(double x, double y) {
    const double z = x * x;
    const double w = z * z;
    const double a1 = z * 0x1.71de357b1fe7dp-19;
    const double a2 = -0x1.a01a019c161d5p-13 + a1;
    const double a3 = z * a2;
    const double a4 = 0x1.111111110f8a6p-7 + a3;
    const double b1 = z * 0x1.5d93a5acfd57cp-33;
    const double b2 = -0x1.ae5e68a2b9cebp-26 + b1;
    const double zw = z * w;
    const double b3 = zw * b2;
    const double r = a4 + b3;
    const double v = z * x;
    const double hy = 0.5 * y;
    const double vr = v * r;
    const double d = hy - vr;
    const double zd = z * d;
    const double e = zd - y;
    const double vs = v * -0x1.5555555555549p-3;
    const double f = e - vs;
    return x - f;
}

/* cos(x + y), |x + y| <= ~pi/4 (fdlibm/musl __cos, math::kernel_cos). */
static double tsf_kernel_cos(double x, double y) {
    const double z = x * x;
    const double w = z * z;
    const double a1 = z * 0x1.a01a019cb159p-16;
    const double a2 = -0x1.6c16c16c15177p-10 + a1;
    const double a3 = z * a2;
    const double a4 = 0x1.555555555554cp-5 + a3;
    const double a5 = z * a4;
    const double b1 = z * -0x1.8fae9be8838d4p-37;
    const double b2 = 0x1.1ee9ebdb4b1c4p-29 + b1;
    const double b3 = z * b2;
    const double b4 = -0x1.27e4f809c52adp-22 + b3;
    const double ww = w * w;
    const double b5 = ww * b4;
    const double r = a5 + b5;
    const double hz = 0.5 * z;
    const double t = 1.0 - hz;
    const double zr = z * r;
    const double xy = x * y;
    const double g = zr - xy;
    const double one_t = 1.0 - t;
    const double h = one_t - hz;
    const double k = h + g;
    return t + k;
}

/* NaN/inf -> NaN; |x| < 2^-26 -> x; |x| <= pi/4 -> kernel; else rem_pio2 and
   [ks, kc, -ks, -kc][n mod 4]. */
double tsf_sin(double x) {
    double y0, y1;
    int n;
    if (isfinite(x) == 0) {
        return NAN;
    }
    if (fabs(x) < 0x1p-26) {
        return x;
    }
    if (fabs(x) <= 0x1.921fb54442d18p-1) {
        return tsf_kernel_sin(x, 0.0);
    }
    n = tsf_rem_pio2(x, &y0, &y1);
    switch ((unsigned)n & 3u) {
    case 0u:
        return tsf_kernel_sin(y0, y1);
    case 1u:
        return tsf_kernel_cos(y0, y1);
    case 2u:
        return -tsf_kernel_sin(y0, y1);
    default:
        return -tsf_kernel_cos(y0, y1);
    }
}

/* NaN/inf -> NaN; |x| < 2^-27 -> 1; |x| <= pi/4 -> kernel; else rem_pio2 and
   [kc, -ks, -kc, ks][n mod 4]. */
double tsf_cos(double x) {
    double y0, y1;
    int n;
    if (isfinite(x) == 0) {
        return NAN;
    }
    if (fabs(x) < 0x1p-27) {
        return 1.0;
    }
    if (fabs(x) <= 0x1.921fb54442d18p-1) {
        return tsf_kernel_cos(x, 0.0);
    }
    n = tsf_rem_pio2(x, &y0, &y1);
    switch ((unsigned)n & 3u) {
    case 0u:
        return tsf_kernel_cos(y0, y1);
    case 1u:
        return -tsf_kernel_sin(y0, y1);
    case 2u:
        return -tsf_kernel_cos(y0, y1);
    default:
        return tsf_kernel_sin(y0, y1);
    }
}

/* ---------------------------------------------------------------- modes */

int tsf_select_mode(uint8_t mode, int k, uint8_t *flags) {
    if ((int)mode < k) {
        return (int)mode;
    }
    *flags = (uint8_t)(*flags | TSF_FLAG_MODE_OUT_OF_RANGE);
    return 0;
}

/* ------------------------------------------------------------- triggers */

int tsf_periodic_decide(uint32_t *count, uint32_t every) {
    int fire = 0;
    if (*count == 0u) {
        fire = 1;
    }
    if (*count != UINT32_MAX) {
        *count = *count + 1u;
    }
    if (*count >= every) {
        *count = 0;
    }
    return fire;
}

/* ------------------------------------------- binary64 (e^v - 1)/v */

/* tsf-runtime's math::EXPREL_COEFFS: 1/(k+1)!, k = 0..14 (the same
   literals). */
static const double tsf_exprel_c[15] = {
    1.0,
    0.5,
    0.16666666666666666,
    0.041666666666666664,
    0.008333333333333333,
    0.001388888888888889,
    0.0001984126984126984,
    2.48015873015873e-05,
    2.7557319223985893e-06,
    2.755731922398589e-07,
    2.505210838544172e-08,
    2.08767569878681e-09,
    1.6059043836821613e-10,
    1.1470745597729725e-11,
    7.647163731819816e-13,
};

/* tsf-runtime's math::exprel: |v| < 0.5 (math::EXPREL_SMALL) the degree-14
   Taylor polynomial by Horner, one product per statement (bit for bit the
   Rust runtime's); otherwise (tsf_exp(v) - 1)/v; +inf gives +inf, -inf 0,
   NaN NaN. */
static double tsf_exprel_f64(double v) {
    if (fabs(v) < 0.5) {
        double p = tsf_exprel_c[14];
        int k;
        for (k = 13; k >= 0; k--) {
            const double t = p * v;
            p = t + tsf_exprel_c[k];
        }
        return p;
    }
    if (v == HUGE_VAL) {
        return v; /* +inf: (inf - 1)/inf would be NaN */
    }
    return (tsf_exp(v) - 1.0) / v;
}

/* ------------------------------------------- elementary functions, double */

/* The runtime's functions (above), libm's sqrt and fabs (correctly rounded
   and exact: the same bits as math::sqrt and the runtime's fabs). */
double tsf_sqrt(double v) {
    return sqrt(v);
}

double tsf_fabs(double v) {
    return fabs(v);
}

/* math::sinc: |v| < 2^-13 (math::SINC_SMALL): 1 - v*v/6 (truncation error
   < 2^-59); otherwise tsf_sin(v)/v. */
double tsf_sinc(double v) {
    if (fabs(v) < 0x1p-13) {
        const double d2 = v * v;
        return 1.0 - d2 / 6.0;
    }
    return tsf_sin(v) / v;
}

double tsf_exprel(double v) {
    return tsf_exprel_f64(v);
}

double tsf_atan(double v) {
    return tsf_atan_f64(v);
}

/* ------------------------------------------- elementary functions, float */

/* tsf-runtime's math::expf, sqrtf, atanf, sinf, cosf, sincf and exprelf
   (runtime/src/math/single.rs), operation by operation in binary32: no
   double operation, so a single-precision FPU runs them without a
   double-precision routine. Bit patterns through memcpy. */

static uint32_t tsf_f32_bits(float v) {
    uint32_t b;
    (void)memcpy(&b, &v, sizeof b);
    return b;
}

static float tsf_f32_from_bits(uint32_t b) {
    float v;
    (void)memcpy(&v, &b, sizeof v);
    return v;
}

/* 2^k for -126 <= k <= 127 (k clamped). */
static float tsf_pow2f(int k) {
    const int c = k < -126 ? -126 : (k > 127 ? 127 : k);
    const int biased = c + 127;
    const uint32_t field = (uint32_t)biased;
    return tsf_f32_from_bits(field << 23);
}

/* e^v: NaN -> NaN, v > 88.72283 -> inf, v <= -103.972084 -> 0,
   |v| < 2^-14 -> 1 + v; k = trunc(v/ln2 +- 1/2), r = (v - k LN2_HI) - k LN2_LO,
   c = r - s (P1 + s P2), y = 1 - ((lo - r c/(2 - c)) - hi), times 2^k. */
float tsf_expf(float x) {
    if (isnan(x) != 0) {
        return x;
    }
    if (x > 88.72283f) {
        return HUGE_VALF;
    }
    if (x <= -103.972084f) {
        return 0.0f;
    }
    if (fabsf(x) < 0x1p-14f) {
        return 1.0f + x;
    }
    {
        const float half = x < 0.0f ? -0.5f : 0.5f;
        const float xl = x * 1.442695f;
        const float kr = xl + half;
        const int k = (int)kr;
        const float kf = (float)k;
        const float kh = kf * 0.69314575f;
        const float hi = x - kh;
        const float lo = kf * 1.4286068e-6f;
        const float r = hi - lo;
        const float s = r * r;
        const float sp2 = s * -0.0027667333f;
        const float p = 0.16666625f + sp2;
        const float sp = s * p;
        const float c = r - sp;
        const float rc = r * c;
        const float q = rc / (2.0f - c);
        const float y = 1.0f - ((lo - q) - hi);
        if (k > 127) {
            const float y2 = y * 2.0f;
            return y2 * tsf_pow2f(k - 1);
        }
        if (k < -125) {
            const float ys = y * tsf_pow2f(k + 100);
            return ys * tsf_pow2f(-100);
        }
        return y * tsf_pow2f(k);
    }
}

/* Correctly rounded: C's sqrtf (IEEE), the runtime's integer sqrtf. */
float tsf_sqrtf(float v) {
    return sqrtf(v);
}

float tsf_fabsf(float v) {
    return fabsf(v);
}

/* math::ATANF_J16: atan(j/16) in binary32, high and low. */
static const float tsf_atanf_j16[40][2] = {
    {0.0f, 0e0f},
    {0.06241881f, -1.0272779e-9f},
    {0.124354996f, -1.2403822e-9f},
    {0.18534794f, 5.4976326e-9f},
    {0.24497867f, -3.1786778e-9f},
    {0.30288488f, -8.353086e-9f},
    {0.35877067f, 1.7639499e-9f},
    {0.41241044f, 3.5366268e-9f},
    {0.4636476f, 5.0121587e-9f},
    {0.5123895f, -2.075692e-8f},
    {0.5585993f, 2.2111598e-8f},
    {0.60228735f, -5.9501493e-9f},
    {0.6435011f, 5.8689373e-9f},
    {0.68231654f, 1.3202995e-8f},
    {0.71883f, 1.01883355e-8f},
    {0.7531513f, -1.660708e-8f},
    {0.7853982f, -2.1855694e-8f},
    {0.81569195f, -2.4620789e-8f},
    {0.844154f, -1.41691165e-8f},
    {0.87090343f, 2.470642e-8f},
    {0.8960554f, -1.5800207e-8f},
    {0.9197196f, 2.8514785e-8f},
    {0.94200003f, 8.908211e-9f},
    {0.96299434f, -6.400973e-9f},
    {0.98279375f, -2.5131424e-8f},
    {1.0014831f, 5.2922932e-8f},
    {1.0191413f, 2.785247e-8f},
    {1.0358412f, 2.6431042e-8f},
    {1.0516502f, 4.603684e-8f},
    {1.0666304f, 1.851388e-9f},
    {1.080839f, -3.7354035e-8f},
    {1.0943289f, 2.7011131e-8f},
    {1.1071488f, -4.872355e-8f},
    {1.1193433f, -4.5549893e-8f},
    {1.1309538f, -4.4778165e-8f},
    {1.1420183f, -1.882739e-8f},
    {1.152572f, -3.8573823e-8f},
    {1.1626472f, -2.4274646e-8f},
    {1.1722739f, 6.8456396e-9f},
    {1.1814796f, 3.1711938e-8f}
};

/* math::ATANF_COMP_J16: pi/2 - atan(j/16), high and low. */
static const float tsf_atanf_comp_j16[8][2] = {
    {1.5707964f, -4.371139e-8f},
    {1.5083776f, -3.523353e-8f},
    {1.4464413f, 3.948538e-8f},
    {1.3854483f, 4.0197946e-8f},
    {1.3258177f, -4.053271e-8f},
    {1.2679114f, 2.4246342e-8f},
    {1.2120256f, 1.4129305e-8f},
    {1.1583859f, 1.2356628e-8f}
};

/* atan(t) - t for |t| <= 1/8: t (s Q(s)), Q = -1/3, 1/5, -1/7, 1/9. */
static float tsf_atanf_tail(float t) {
    const float s = t * t;
    const float q4 = s * 0.11111111f;
    const float q3 = s * (-0.14285715f + q4);
    const float q2 = s * (0.2f + q3);
    const float q = -0.33333334f + q2;
    const float sq = s * q;
    return t * sq;
}

/* math::atanf: math::atan's algorithm in binary32. */
float tsf_atanf(float x) {
    float a;
    float r;
    if (isnan(x) != 0) {
        return x;
    }
    a = fabsf(x);
    if (a < 0x1p-12f) {
        return x;
    }
    if (a > 0x1p26f) {
        r = tsf_atanf_comp_j16[0][0] + tsf_atanf_comp_j16[0][1];
    } else if (a < 0.125f) {
        r = a + tsf_atanf_tail(a);
    } else if (a <= 2.4375f) {
        const float a16 = a * 16.0f;
        const float jr = a16 + 0.5f;
        const int j = (int)jr;
        const float c = (float)j * 0.0625f;
        const float num = a - c;
        const float ac = a * c;
        const float den = 1.0f + ac;
        const float t = num / den;
        const float tt = t + tsf_atanf_tail(t);
        const float hi = (j >= 0 && j < 40) ? tsf_atanf_j16[j][0] : 0.0f;
        const float lo = (j >= 0 && j < 40) ? tsf_atanf_j16[j][1] : 0.0f;
        const float lt = lo + tt;
        r = hi + lt;
    } else {
        const float q16 = 16.0f / a;
        const float jr = q16 + 0.5f;
        const int j = (int)jr;
        const float c = (float)j * 0.0625f;
        const float ac = a * c;
        const float num = 1.0f - ac;
        const float den = a + c;
        const float t = num / den;
        const float tt = t + tsf_atanf_tail(t);
        const float hi = (j >= 0 && j < 8) ? tsf_atanf_comp_j16[j][0] : 0.0f;
        const float lo = (j >= 0 && j < 8) ? tsf_atanf_comp_j16[j][1] : 0.0f;
        const float lt = lo - tt;
        r = hi + lt;
    }
    return signbit(x) ? -r : r;
}

/* 64 bits of 2/pi from 0-based bit position pos (negative: leading zeros). */
static uint64_t tsf_two_over_pi_bits(int pos) {
    if (pos < 0) {
        const int neg = -pos;
        return neg >= 64 ? 0u : tsf_two_over_pi_word(0) >> (unsigned)neg;
    } else {
        const int k = pos / 64;
        const int rem = pos % 64;
        const unsigned sh = (unsigned)rem;
        if (sh == 0u) {
            return tsf_two_over_pi_word(k);
        }
        return (tsf_two_over_pi_word(k) << sh) | (tsf_two_over_pi_word(k + 1) >> (64u - sh));
    }
}

/* math::rem_pio2f: x = n pi/2 + y for finite |x| > pi/4, with integers
   (96 bits of 2/pi from bit e - 2, quadrant and 64 fraction bits of m W,
   rounded to the nearest quadrant; y from the top 32 bits of |f| times pi/2
   in Q31, one rounding). Returns n, writes y. */
static int tsf_rem_pio2f(float x, float *y) {
    const uint32_t bits = tsf_f32_bits(x);
    const uint32_t ebits = (bits >> 23) & 0xffu;
    const int e = (int)ebits - 150;
    const uint32_t mbits = (bits & 0x007fffffu) | 0x00800000u;
    const uint64_t m = (uint64_t)mbits;
    const uint64_t hi64 = tsf_two_over_pi_bits(e - 2);
    const uint64_t lo32 = tsf_two_over_pi_bits(e + 62) >> 32;
    const uint64_t p2 = m * lo32;
    const uint64_t p1 = m * (hi64 & 0xffffffffu) + (p2 >> 32);
    const uint64_t p0 = m * (hi64 >> 32) + (p1 >> 32);
    const uint64_t quadrant = (p0 >> 30) & 3u;
    int n = (int)quadrant;
    const uint64_t frac = ((p0 & 0x3fffffffu) << 34) | ((p1 & 0xffffffffu) << 2) |
                          ((p2 & 0xffffffffu) >> 30);
    uint64_t mag = frac;
    int neg = 0;
    float v = 0.0f;
    if ((frac >> 63) != 0u) {
        n = n + 1;
        mag = (~frac) + 1u;
        neg = 1;
    }
    if (mag != 0u) {
        int lz = 0;
        uint64_t norm = mag;
        while ((norm >> 63) == 0u) {
            norm = norm << 1;
            lz = lz + 1;
        }
        {
            const uint64_t prod = (norm >> 32) * 0xc90fdaa2u;
            v = (float)prod * tsf_pow2f(-63 - lz);
        }
    }
    if (neg != 0) {
        v = -v;
    }
    if (x < 0.0f) {
        *y = -v;
        return -n;
    }
    *y = v;
    return n;
}

/* sin(y), |y| <= ~pi/4: y + (y z)(S1 + z(S2 + z(S3 + z S4))), z = y y. */
static float tsf_kernel_sinf(float y) {
    const float z = y * y;
    const float p4 = z * 2.7557318e-6f;
    const float p3 = z * (-1.984127e-4f + p4);
    const float p2 = z * (8.3333335e-3f + p3);
    const float p = -0.16666667f + p2;
    const float yz = y * z;
    const float t = yz * p;
    return y + t;
}

/* cos(y), |y| <= ~pi/4: 1 - (z/2 - (z z)(C1 + z(C2 + z(C3 + z C4)))). */
static float tsf_kernel_cosf(float y) {
    const float z = y * y;
    const float c4 = z * -2.7557318e-7f;
    const float c3 = z * (2.4801587e-5f + c4);
    const float c2 = z * (-0.0013888889f + c3);
    const float c = 0.041666668f + c2;
    const float zz = z * z;
    const float q = zz * c;
    const float hz = 0.5f * z;
    return 1.0f - (hz - q);
}

float tsf_sinf(float x) {
    float y;
    int n;
    if (isfinite(x) == 0) {
        return NAN;
    }
    if (fabsf(x) < 0x1p-12f) {
        return x;
    }
    if (fabsf(x) <= 0.7853981f) {
        return tsf_kernel_sinf(x);
    }
    n = tsf_rem_pio2f(x, &y);
    switch ((unsigned)n & 3u) {
    case 0u:
        return tsf_kernel_sinf(y);
    case 1u:
        return tsf_kernel_cosf(y);
    case 2u:
        return -tsf_kernel_sinf(y);
    default:
        return -tsf_kernel_cosf(y);
    }
}

float tsf_cosf(float x) {
    float y;
    int n;
    if (isfinite(x) == 0) {
        return NAN;
    }
    if (fabsf(x) < 0x1p-12f) {
        return 1.0f;
    }
    if (fabsf(x) <= 0.7853981f) {
        return tsf_kernel_cosf(x);
    }
    n = tsf_rem_pio2f(x, &y);
    switch ((unsigned)n & 3u) {
    case 0u:
        return tsf_kernel_cosf(y);
    case 1u:
        return -tsf_kernel_sinf(y);
    case 2u:
        return -tsf_kernel_cosf(y);
    default:
        return tsf_kernel_sinf(y);
    }
}

/* sin(v)/v: |v| < 2^-6 (math::SINCF_SMALL): 1 - v*v/6. */
float tsf_sincf(float v) {
    if (fabsf(v) < 0x1p-6f) {
        const float d2 = v * v;
        return 1.0f - d2 / 6.0f;
    }
    return tsf_sinf(v) / v;
}

/* math::EXPRELF_COEFFS: 1/(k+1)!, k = 0..8, in binary32. */
static const float tsf_exprelf_c[9] = {
    1.0f, 0.5f, 0.16666667f, 0.041666668f, 8.3333335e-3f, 0.0013888889f, 1.984127e-4f,
    2.4801587e-5f, 2.7557318e-6f
};

/* (e^v - 1)/v: |v| < 0.5 the degree-8 series by Horner from c_8; +inf -> +inf;
   otherwise (tsf_expf(v) - 1)/v. */
float tsf_exprelf(float v) {
    if (fabsf(v) < 0.5f) {
        float p = tsf_exprelf_c[8];
        int k;
        for (k = 7; k >= 0; k--) {
            const float t = p * v;
            p = t + tsf_exprelf_c[k];
        }
        return p;
    }
    if (v == HUGE_VALF) {
        return v;
    }
    return (tsf_expf(v) - 1.0f) / v;
}

/* ------------------------------------------------- the two instantiations */

#define TSF_RUNTIME_INSTANCE
#define TSF_R double
#define TSF_FN(name) name
#define TSF_TINY_SCALE 0x1p-520
#include "tsf_runtime.c"
#undef TSF_R
#undef TSF_FN
#undef TSF_TINY_SCALE

#define TSF_R float
#define TSF_FN(name) name##f
#define TSF_TINY_SCALE 0x1p-70
#include "tsf_runtime.c"
#undef TSF_R
#undef TSF_FN
#undef TSF_TINY_SCALE
#undef TSF_RUNTIME_INSTANCE

/* ------------------------------------- model-reference adaptive law (double) */

/* tsf_runtime::adaptive, operation by operation: every sum starts from +0
   and adds in index order, one product per statement. */

/* ((0 + a_0 b_0) + a_1 b_1) + ... */
static double tsf_mrac_dot(const double *a, const double *b, int n) {
    double acc = 0.0;
    int k;
    for (k = 0; k < n; k++) {
        const double t = a[k] * b[k];
        acc = acc + t;
    }
    return acc;
}

/* sum_l row_l (s_l - r_l), from +0 in index order. */
static double tsf_mrac_drift(const double *row, const double *s, const double *r, int m) {
    double acc = 0.0;
    int l;
    for (l = 0; l < m; l++) {
        const double e = s[l] - r[l];
        const double t = row[l] * e;
        acc = acc + t;
    }
    return acc;
}

/* v + rate dv projected onto [lo, hi]; v when that is not finite. */
static double tsf_mrac_update(const tsf_adaptation *q, double v, double dv) {
    const double step = q->rate * dv;
    const double next = v + step;
    if (isfinite(next) == 0) {
        return v;
    }
    if (next < q->lo) {
        return q->lo;
    }
    if (next > q->hi) {
        return q->hi;
    }
    return next;
}

/* max(-1, min(1, v)); NaN stays NaN. */
static double tsf_mrac_sat(double v) {
    if (v < -1.0) {
        return -1.0;
    }
    if (v > 1.0) {
        return 1.0;
    }
    return v;
}

/* Whether the n values of v are all finite. */
static int tsf_mrac_finite(const double *v, int n) {
    int all = 1;
    int k;
    for (k = 0; k < n; k++) {
        if (isfinite(v[k]) == 0) {
            all = 0;
        }
    }
    return all;
}

/* The update laws over dt with projection, then the reference model
   (AdaptiveLaw::adapt); ds is scratch space of m values. */
static void tsf_mrac_adapt(const tsf_mrac_law *law, double *a_hat, double *b_hat, double *d_hat,
                           double *s_m, const double *x, const double *h, const double *r,
                           const double *p, const double *u, double dt, double *ds) {
    const int n = law->n, m = law->m;
    int i, k, j;
    for (i = 0; i < law->r; i++) {
        const double dh = dt * h[i];
        for (k = 0; k < m; k++) {
            if (law->a.rate > 0.0) {
                double *row = &a_hat[(i * m + k) * n];
                for (j = 0; j < n; j++) {
                    const double dx = dh * x[j];
                    const double dv = dx * p[k];
                    row[j] = tsf_mrac_update(&law->a, row[j], dv);
                }
            }
            if (law->b.rate > 0.0) {
                const double du = dh * u[k];
                const double dv = du * p[k];
                b_hat[i * m + k] = tsf_mrac_update(&law->b, b_hat[i * m + k], dv);
            }
        }
    }
    if (law->d.rate > 0.0) {
        double sum = 0.0;
        for (k = 0; k < m; k++) {
            sum = sum + fabs(p[k]);
        }
        {
            const double dv = dt * sum;
            *d_hat = tsf_mrac_update(&law->d, *d_hat, dv);
        }
    }
    for (k = 0; k < m; k++) {
        ds[k] = tsf_mrac_drift(&law->a_m[k * m], s_m, r, m);
    }
    for (k = 0; k < m; k++) {
        const double step = dt * ds[k];
        const double next = s_m[k] + step;
        if (isfinite(next) != 0) {
            s_m[k] = next;
        }
    }
}

int tsf_mrac_step(const tsf_mrac_law *law, double *a_hat, double *b_hat, double *d_hat,
                  double *s_m, const double *x, const double *h, const double *r, double dt,
                  double *u, double *work) {
    const int n = law->n, m = law->m;
    double *s = work;
    double *p = &work[m > 0 ? m : 0];
    int i, k, l;
    if (m > 0 && m <= TSF_MRAC_MAX_INPUTS) {
        for (k = 0; k < m; k++) {
            u[k] = 0.0;
        }
    }
    if (!(n > 0 && m > 0 && m <= TSF_MRAC_MAX_INPUTS && law->r >= 0)) {
        return TSF_MRAC_SHAPE;
    }
    if (!((tsf_mrac_finite(x, n) != 0) && (tsf_mrac_finite(h, law->r) != 0) &&
          (tsf_mrac_finite(r, m) != 0) && (isfinite(dt) != 0) && (dt >= 0.0))) {
        return TSF_MRAC_NONFINITE;
    }
    for (k = 0; k < m; k++) {
        s[k] = tsf_mrac_dot(&law->c[k * n], x, n);
    }
    /* p = P eps, eps_l = s_l - s_m_l formed where it is used (same value). */
    for (k = 0; k < m; k++) {
        double acc = 0.0;
        for (l = 0; l < m; l++) {
            const double e = s[l] - s_m[l];
            const double t = law->p[k * m + l] * e;
            acc = acc + t;
        }
        p[k] = acc;
    }
    for (k = 0; k < m; k++) {
        double ax = 0.0, bh = 0.0;
        for (i = 0; i < law->r; i++) {
            const double ai = tsf_mrac_dot(&a_hat[(i * m + k) * n], x, n);
            const double ta = h[i] * ai;
            const double tb = h[i] * b_hat[i * m + k];
            ax = ax + ta;
            bh = bh + tb;
        }
        {
            const double v = tsf_mrac_drift(&law->a_m[k * m], s, r, m);
            const double q = p[k] / law->layer;
            const double w = *d_hat * tsf_mrac_sat(q);
            const double num = v - ax;
            const double top = num - w;
            u[k] = top / bh;
        }
    }
    if (tsf_mrac_finite(u, m) == 0) {
        for (k = 0; k < m; k++) {
            u[k] = 0.0;
        }
        return TSF_MRAC_NONFINITE;
    }
    /* s is no longer needed: its space holds the reference model's drift. */
    tsf_mrac_adapt(law, a_hat, b_hat, d_hat, s_m, x, h, r, p, u, dt, s);
    return TSF_MRAC_OK;
}

#else /* TSF_RUNTIME_INSTANCE: the functions of one real type TSF_R */

/* A constant of the real type. */
#define TSF_C(v) ((TSF_R)(v))

/* ------------------------------------------------------ vector algebra */

TSF_R TSF_FN(tsf_dot)(const TSF_R *a, const TSF_R *b, int n) {
    TSF_R acc;
    int k;
    if (n <= 0) {
        return TSF_C(0);
    }
    acc = a[0] * b[0];
    for (k = 1; k < n; k++) {
        const TSF_R t = a[k] * b[k];
        acc = acc + t;
    }
    return acc;
}

/* tsf_dot for the blend's rows (n >= 1), two products per iteration, still
   added one after the other. */
static TSF_R TSF_FN(tsf_row_dot)(const TSF_R *a, const TSF_R *b, int n) {
    TSF_R acc = a[0] * b[0];
    int k;
    for (k = 1; k + 1 < n; k += 2) {
        const TSF_R t0 = a[k] * b[k];
        const TSF_R t1 = a[k + 1] * b[k + 1];
        acc = acc + t0;
        acc = acc + t1;
    }
    if (k < n) {
        const TSF_R t = a[k] * b[k];
        acc = acc + t;
    }
    return acc;
}

/* sqrt(sum v_k^2), no rescaling. */
static TSF_R TSF_FN(tsf_norm)(const TSF_R *v, int n) {
    return TSF_FN(tsf_sqrt)(TSF_FN(tsf_dot)(v, v, n));
}

/* v'Uv = sum_i v_i (sum_j U_ij v_j), U row-major n x n. */
static TSF_R TSF_FN(tsf_quad_form)(const TSF_R *w, const TSF_R *v, int n) {
    TSF_R acc = TSF_C(0);
    int i;
    for (i = 0; i < n; i++) {
        const TSF_R r = TSF_FN(tsf_dot)(&w[i * n], v, n);
        const TSF_R t = v[i] * r;
        acc = acc + t;
    }
    return acc;
}

/* ----------------------------------------------------------- memberships */

/* Maps into [0, 1]; NaN -> 0. */
static TSF_R TSF_FN(tsf_clamp01)(TSF_R v) {
    if (v >= TSF_C(1)) {
        return TSF_C(1);
    }
    if (v > TSF_C(0)) {
        return v;
    }
    return TSF_C(0);
}

/* (p - q)/(r - s); if r - s overflows, every operand is halved first. */
static TSF_R TSF_FN(tsf_edge_ratio)(TSF_R p, TSF_R q, TSF_R r, TSF_R s) {
    const TSF_R den = r - s;
    if (isfinite(den) != 0) {
        return (p - q) / den;
    } else {
        const TSF_R ph = p * TSF_C(0.5);
        const TSF_R qh = q * TSF_C(0.5);
        const TSF_R rh = r * TSF_C(0.5);
        const TSF_R sh = s * TSF_C(0.5);
        return (ph - qh) / (rh - sh);
    }
}

/* Degree of one term at premise vector z (p values), in [0, 1], never NaN. */
static TSF_R TSF_FN(tsf_degree)(const TSF_FN(tsf_term) *t, const TSF_R *z, int p,
                                const TSF_R *about_points) {
    TSF_R v;
    if (t->var < 0 || t->len < 0 || t->var + t->len > p) {
        return TSF_C(0);
    }
    switch (t->kind) {
    case TSF_TERM_TRAP: {
        const TSF_R x = z[t->var];
        const TSF_R a = t->prm[0], b = t->prm[1], c = t->prm[2], d = t->prm[3];
        if (!(x >= a && x <= d)) {
            v = TSF_C(0);
        } else if (x >= b && x <= c) {
            v = TSF_C(1);
        } else if (x < b) {
            v = TSF_FN(tsf_edge_ratio)(x, a, b, a);
        } else {
            v = TSF_FN(tsf_edge_ratio)(d, x, d, c);
        }
        break;
    }
    case TSF_TERM_GAUSS: {
        const TSF_R w = (z[t->var] - t->prm[0]) / t->prm[1];
        const TSF_R w2 = w * w;
        const TSF_R e = TSF_C(0.5) * w2;
        v = TSF_FN(tsf_exp)(-e);
        break;
    }
    case TSF_TERM_SIGMOID: {
        const TSF_R d = z[t->var] - t->prm[1];
        const TSF_R k = t->prm[0] * d;
        const TSF_R e = TSF_FN(tsf_exp)(-k);
        v = TSF_C(1) / (TSF_C(1) + e);
        break;
    }
    default: {
        TSF_R d2 = TSF_C(0);
        int k;
        for (k = 0; k < t->len; k++) {
            const TSF_R d = z[t->var + k] - about_points[t->point + k];
            const TSF_R dd = d * d;
            d2 = d2 + dd;
        }
        {
            const TSF_R s2 = t->prm[0] * t->prm[0];
            const TSF_R e = TSF_C(0.5) * (d2 / s2);
            v = TSF_FN(tsf_exp)(-e);
        }
        break;
    }
    }
    return TSF_FN(tsf_clamp01)(v);
}

/* ------------------------------------------------------- controller step */

/* Rule weights (product t-norm) from the degrees of the distinct terms:
   w_i = ((1 * deg[k_1]) * deg[k_2]) * ... over rule i's indices (an index
   out of range is degree 0). */
static void TSF_FN(tsf_rule_weights)(const TSF_FN(tsf_controller) *c, const TSF_R *deg,
                                     TSF_R *w) {
    const unsigned d = c->d > 0 ? (unsigned)c->d : 0u;
    int i, k;
    for (i = 0; i < c->r; i++) {
        TSF_R acc = TSF_C(1);
        for (k = c->rule_factors[i]; k < c->rule_factors[i + 1]; k++) {
            const unsigned f = (unsigned)c->factors[k];
            acc = acc * (f < d ? deg[f] : TSF_C(0));
        }
        w[i] = acc;
    }
}

/* In place: h_i = w_i / sum w (weights NaN or <= 0 count as 0, one pass
   clamps and sums); 0 if no rule fires. */
static int TSF_FN(tsf_normalize)(TSF_R *h, int r) {
    TSF_R s = TSF_C(0);
    int i;
    for (i = 0; i < r; i++) {
        h[i] = h[i] > TSF_C(0) ? h[i] : TSF_C(0);
        s = s + h[i];
    }
    if (!(s > TSF_C(0) && isfinite(s))) {
        return 0;
    }
    for (i = 0; i < r; i++) {
        h[i] = h[i] / s;
    }
    return 1;
}

/* Nearest rule centre with operands scaled by `scale`; *found is 0 if every
   distance was NaN. Ties and NaN go to the lowest index. */
static int TSF_FN(tsf_nearest_scaled)(const TSF_FN(tsf_controller) *c, const TSF_R *z,
                                      TSF_R scale, TSF_R *best_d, int *found) {
    const int stride = c->p > 0 ? c->p : 1;
    int best = 0, i, k;
    *found = 0;
    for (i = 0; i < c->r; i++) {
        TSF_R d = TSF_C(0);
        int better;
        for (k = 0; k < c->p; k++) {
            const TSF_R a = z[k] * scale;
            const TSF_R b = c->centres[i * stride + k] * scale;
            const TSF_R e = a - b;
            const TSF_R e2 = e * e;
            d = d + e2;
        }
        better = *found ? d < *best_d : !isnan(d);
        if (better != 0) {
            best = i;
            *best_d = d;
            *found = 1;
        }
    }
    return best;
}

/* Index of the nearest rule centre; overflowing distances are recomputed
   with operands scaled by TSF_TINY_SCALE. */
static int TSF_FN(tsf_nearest_rule)(const TSF_FN(tsf_controller) *c, const TSF_R *z) {
    TSF_R d = TSF_C(0);
    int found;
    int best = TSF_FN(tsf_nearest_scaled)(c, z, TSF_C(1), &d, &found);
    if (found && !isfinite(d)) {
        best = TSF_FN(tsf_nearest_scaled)(c, z, TSF_C(TSF_TINY_SCALE), &d, &found);
    }
    return best;
}

/* u = sum_j h_j (F_j x), rules whose h_j is not > 0 skipped. */
static void TSF_FN(tsf_blend)(const TSF_FN(tsf_controller) *c, const TSF_R *h, const TSF_R *x,
                              TSF_R *u) {
    int j, s;
    for (s = 0; s < c->m; s++) {
        u[s] = TSF_C(0);
    }
    if (c->n <= 0) {
        return;
    }
    for (j = 0; j < c->r; j++) {
        if (!(h[j] > TSF_C(0))) {
            continue;
        }
        for (s = 0; s < c->m; s++) {
            const TSF_R f = TSF_FN(tsf_row_dot)(&c->gains[(j * c->m + s) * c->n], x, c->n);
            const TSF_R t = h[j] * f;
            u[s] = u[s] + t;
        }
    }
}

/* In place: |u_s| <= b_s, b_s = u_max_s if u_max_s >= 0 else 0; NaN -> 0,
   +-inf -> +-b_s (0 if b_s is infinite). Returns the flags. */
static uint8_t TSF_FN(tsf_saturate)(const TSF_FN(tsf_controller) *c, TSF_R *u) {
    uint8_t flags = 0;
    int s;
    for (s = 0; s < c->m; s++) {
        const TSF_R b = c->u_max[s] >= TSF_C(0) ? c->u_max[s] : TSF_C(0);
        TSF_R v = u[s];
        if (!isfinite(v)) {
            flags |= TSF_FLAG_COMMAND_NONFINITE;
            if (isnan(v) || !isfinite(b)) {
                v = TSF_C(0);
            }
        }
        if (v > b) {
            flags |= TSF_FLAG_SATURATED;
            u[s] = b;
        } else if (v < -b) {
            flags |= TSF_FLAG_SATURATED;
            u[s] = -b;
        } else {
            u[s] = v;
        }
    }
    return flags;
}

uint8_t TSF_FN(tsf_step_with_premises)(const TSF_FN(tsf_controller) *c, const TSF_R *x,
                                       const TSF_R *z, TSF_R *deg, TSF_R *h, TSF_R *u) {
    uint8_t flags = 0;
    int i;
    for (i = 0; i < c->n; i++) {
        if (!isfinite(x[i])) {
            flags |= TSF_FLAG_STATE_NONFINITE;
        }
    }
    for (i = 0; i < c->p; i++) {
        if (!isfinite(z[i])) {
            flags |= TSF_FLAG_PREMISE_NONFINITE;
        }
    }
    if ((flags & (TSF_FLAG_STATE_NONFINITE | TSF_FLAG_PREMISE_NONFINITE)) != 0u) {
        for (i = 0; i < c->r; i++) {
            h[i] = TSF_C(0);
        }
        for (i = 0; i < c->m; i++) {
            u[i] = TSF_C(0);
        }
        return flags;
    }
    for (i = 0; i < c->d; i++) {
        deg[i] = TSF_FN(tsf_degree)(&c->terms[i], z, c->p, c->about_points);
    }
    TSF_FN(tsf_rule_weights)(c, deg, h);
    if (!TSF_FN(tsf_normalize)(h, c->r)) {
        for (i = 0; i < c->r; i++) {
            h[i] = TSF_C(0);
        }
        h[TSF_FN(tsf_nearest_rule)(c, z)] = TSF_C(1);
        flags |= TSF_FLAG_NO_RULE_FIRED;
    }
    TSF_FN(tsf_blend)(c, h, x, u);
    flags |= TSF_FN(tsf_saturate)(c, u);
    return flags;
}

/* ------------------------------------------------------------- observer */

void TSF_FN(tsf_observer_premise_state)(const TSF_FN(tsf_observer) *o, const TSF_R *xhat,
                                        const TSF_R *y, TSF_R *v) {
    const int n = o->ctl->n;
    int k;
    for (k = 0; k < n; k++) {
        v[k] = o->output_map != NULL ? TSF_FN(tsf_dot)(&o->output_map[k * o->q], y, o->q)
                                     : xhat[k];
    }
}

/* next = sum_i h_i ((Phi_i xhat + Gu_i u) + Gy_i y), rules whose h_i is not
   > 0 skipped, accumulated from 0 rule by rule. */
static void TSF_FN(tsf_observer_update)(const TSF_FN(tsf_observer) *o, const TSF_R *h,
                                        const TSF_R *xhat, const TSF_R *u, const TSF_R *y,
                                        TSF_R *next) {
    const int n = o->ctl->n, m = o->ctl->m, q = o->q;
    int i, k;
    for (k = 0; k < n; k++) {
        next[k] = TSF_C(0);
    }
    for (i = 0; i < o->ctl->r; i++) {
        if (!(h[i] > TSF_C(0))) {
            continue;
        }
        for (k = 0; k < n; k++) {
            const TSF_R a = TSF_FN(tsf_dot)(&o->phi[(i * n + k) * n], xhat, n);
            const TSF_R b = TSF_FN(tsf_dot)(&o->gu[(i * n + k) * m], u, m);
            const TSF_R c = TSF_FN(tsf_dot)(&o->gy[(i * n + k) * q], y, q);
            const TSF_R ab = a + b;
            const TSF_R v = ab + c;
            const TSF_R t = h[i] * v;
            next[k] = next[k] + t;
        }
    }
}

uint8_t TSF_FN(tsf_observer_step)(const TSF_FN(tsf_observer) *o, TSF_R *xhat, const TSF_R *y,
                                  const TSF_R *z, TSF_R *deg, TSF_R *h, TSF_R *u, TSF_R *next) {
    const TSF_FN(tsf_controller) *c = o->ctl;
    uint8_t flags = 0;
    int estimate_ok = 1, i;
    for (i = 0; i < c->n; i++) {
        if (!isfinite(xhat[i])) {
            estimate_ok = 0;
        }
    }
    for (i = 0; i < o->q; i++) {
        if (!isfinite(y[i])) {
            flags |= TSF_FLAG_STATE_NONFINITE;
        }
    }
    if (!estimate_ok) {
        flags |= TSF_FLAG_STATE_NONFINITE;
    }
    for (i = 0; i < c->p; i++) {
        if (!isfinite(z[i])) {
            flags |= TSF_FLAG_PREMISE_NONFINITE;
        }
    }
    if ((flags & (TSF_FLAG_STATE_NONFINITE | TSF_FLAG_PREMISE_NONFINITE)) != 0u) {
        if (!estimate_ok) {
            for (i = 0; i < c->n; i++) {
                xhat[i] = TSF_C(0);
            }
            flags |= TSF_FLAG_ESTIMATE_RESET;
        }
        for (i = 0; i < c->r; i++) {
            h[i] = TSF_C(0);
        }
        for (i = 0; i < c->m; i++) {
            u[i] = TSF_C(0);
        }
        return flags;
    }
    flags = TSF_FN(tsf_step_with_premises)(c, xhat, z, deg, h, u);
    TSF_FN(tsf_observer_update)(o, h, xhat, u, y, next);
    for (i = 0; i < c->n; i++) {
        if (!isfinite(next[i])) {
            estimate_ok = 0;
        }
    }
    for (i = 0; i < c->n; i++) {
        xhat[i] = estimate_ok ? next[i] : TSF_C(0);
    }
    if (!estimate_ok) {
        flags |= TSF_FLAG_ESTIMATE_RESET;
    }
    return flags;
}

/* -------------------------------------------------------------- triggers */

int TSF_FN(tsf_relative_decide)(const TSF_R *weight, TSF_R nu, TSF_R *last, int *has_last,
                                const TSF_R *x, TSF_R *e, int n) {
    int k;
    if (!*has_last) {
        for (k = 0; k < n; k++) {
            last[k] = x[k];
            e[k] = TSF_C(0);
        }
        *has_last = 1;
        return 1;
    }
    for (k = 0; k < n; k++) {
        e[k] = x[k] - last[k];
    }
    {
        const TSF_R lhs = TSF_FN(tsf_quad_form)(weight, e, n);
        const TSF_R q = TSF_FN(tsf_quad_form)(weight, last, n);
        const TSF_R rhs = nu * q;
        if (lhs < rhs) {
            return 0;
        }
    }
    for (k = 0; k < n; k++) {
        last[k] = x[k];
    }
    return 1;
}

/* The law's threshold after a transmission with jump e:
   g = (mu1 * (2/pi)) * atan(mu2 * (||e|| - mu3)), cand = nu * (1 - g), then
   the bounds. */
static TSF_R TSF_FN(tsf_adaptive_nu)(const TSF_FN(tsf_adaptive_law) *law, TSF_R nu,
                                     const TSF_R *e, int n) {
    const TSF_R a = TSF_FN(tsf_norm)(e, n) - law->mu3;
    const TSF_R b = law->mu2 * a;
    const TSF_R k = law->mu1 * TSF_C(0.6366197723675814);
    const TSF_R g = k * TSF_FN(tsf_atan)(b);
    const TSF_R cand = nu * (TSF_C(1) - g);
    if (!(cand >= law->nu_min)) {
        /* below the bound, or NaN */
        return law->nu_min;
    }
    if (cand > law->nu_max) {
        return law->nu_max >= law->nu_min ? law->nu_max : law->nu_min;
    }
    return cand;
}

int TSF_FN(tsf_adaptive_decide)(const TSF_FN(tsf_adaptive_law) *law, const TSF_R *weight,
                                TSF_R *nu, TSF_R *last, int *has_last, const TSF_R *x, TSF_R *e,
                                int n) {
    int first = 0;
    if (*has_last == 0) {
        first = 1;
    }
    if (!TSF_FN(tsf_relative_decide)(weight, *nu, last, has_last, x, e, n)) {
        return 0;
    }
    if (!first) {
        *nu = TSF_FN(tsf_adaptive_nu)(law, *nu, e, n);
    }
    return 1;
}

int TSF_FN(tsf_mixed_decide)(TSF_R beta, TSF_R rho, TSF_R *last, int *has_last,
                             const TSF_R *sigma, TSF_R *d, int n) {
    int k;
    if (*has_last != 0) {
        for (k = 0; k < n; k++) {
            d[k] = last[k] - sigma[k];
        }
        {
            const TSF_R xi = TSF_FN(tsf_norm)(d, n);
            const TSF_R bs = beta * TSF_FN(tsf_norm)(sigma, n);
            const TSF_R threshold = bs + rho;
            if (xi < threshold) {
                return 0;
            }
        }
    }
    for (k = 0; k < n; k++) {
        last[k] = sigma[k];
    }
    *has_last = 1;
    return 1;
}

#undef TSF_C

#endif /* TSF_RUNTIME_INSTANCE */
