// The paper's objective and its gradient, one GPU thread per sample (design, goal, start): what
// sim/optimize/tensor.rs computes with candle ops, fused, so that a step is one launch instead of
// hundreds of small kernels and host round trips. Compiled at run time by NVRTC with
// --fmad=false (no contracted multiply-adds: the CPU rounds every product and sum on its own).
//
// The arithmetic follows tensor.rs operation by operation where the order of a sum matters
// (forward kinematics, the capsule ends, the closest points of gaps.rs, the pair sums of the
// collision cost); the gradient is the chain rule written out, with the closest points held on
// their segments (the envelope theorem, as gaps.rs and analytic.rs take it). Constants come in as
// arguments from the Rust side, their one home.

#define MAX_DOF 16
#define MAX_CAPSULES 64

struct Constants {
    double distance_weight;
    double rotation_weight;
    double collision_weight;
    double threshold;
    double dead_zone;
    double sqrt_floor;
    double point_segment_m2;
    double meet;
};

__device__ static inline double dot3(const double* a, const double* b) {
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
}

// sin, cos, exp and atan2 from IEEE additions, multiplications, divisions and exact bit
// operations alone, in the order of sim/optimize/portable.rs (musl's algorithms), so that the
// GPU rounds as the CPU does: libdevice's and libm's last bits differ, and 200 Adam steps through
// the objective's kinks grow one ulp into another design.
__device__ static inline double pg_f(unsigned long long bits) {
    return __longlong_as_double((long long)bits);
}

__device__ static void pg_rem_pio2(double x, long long* n_out, double* y0, double* y1) {
    const unsigned long long parts[3][2] = {
        {0x3FF921FB54400000ULL, 0x3DD0B4611A626331ULL},
        {0x3DD0B4611A600000ULL, 0x3BA3198A2E037073ULL},
        {0x3BA3198A2E000000ULL, 0x397B839A252049C1ULL},
    };
    double n = round(x * pg_f(0x3FE45F306DC9C883ULL));
    double r = x - n * pg_f(parts[0][0]);
    double w = n * pg_f(parts[0][1]);
    for (int i = 1; i < 3; ++i) {
        double t = r;
        w = n * pg_f(parts[i][0]);
        r = t - w;
        w = n * pg_f(parts[i][1]) - ((t - r) - w);
    }
    *y0 = r - w;
    *y1 = (r - *y0) - w;
    *n_out = (long long)n;
}

__device__ static double pg_kernel_sin(double x, double y) {
    double z = x * x;
    double w = z * z;
    double r = (pg_f(0x3F8111111110F8A6ULL) + z * (pg_f(0xBF2A01A019C161D5ULL) + z * pg_f(0x3EC71DE357B1FE7DULL))) +
               (z * w) * (pg_f(0xBE5AE5E68A2B9CEBULL) + z * pg_f(0x3DE5D93A5ACFD57CULL));
    double v = z * x;
    return x - ((z * (0.5 * y - v * r) - y) - v * pg_f(0xBFC5555555555549ULL));
}

__device__ static double pg_kernel_cos(double x, double y) {
    double z = x * x;
    double w = z * z;
    double r = z * (pg_f(0x3FA555555555554CULL) + z * (pg_f(0xBF56C16C16C15177ULL) + z * pg_f(0x3EFA01A019CB1590ULL))) +
               (w * w) * (pg_f(0xBE927E4F809C52ADULL) + z * (pg_f(0x3E21EE9EBDB4B1C4ULL) + z * pg_f(0xBDA8FAE9BE8838D4ULL)));
    double hz = 0.5 * z;
    double v = 1.0 - hz;
    return v + (((1.0 - v) - hz) + (z * r - x * y));
}

__device__ static double pg_sin(double x) {
    long long n;
    double y0, y1;
    pg_rem_pio2(x, &n, &y0, &y1);
    switch (n & 3) {
        case 0: return pg_kernel_sin(y0, y1);
        case 1: return pg_kernel_cos(y0, y1);
        case 2: return -pg_kernel_sin(y0, y1);
        default: return -pg_kernel_cos(y0, y1);
    }
}

__device__ static double pg_cos(double x) {
    long long n;
    double y0, y1;
    pg_rem_pio2(x, &n, &y0, &y1);
    switch (n & 3) {
        case 0: return pg_kernel_cos(y0, y1);
        case 1: return -pg_kernel_sin(y0, y1);
        case 2: return -pg_kernel_cos(y0, y1);
        default: return pg_kernel_sin(y0, y1);
    }
}

__device__ static double pg_scale(double y, long long n) {
    double up = pg_f(0x7FE0000000000000ULL), down = pg_f(0x0360000000000000ULL);
    if (n > 1023) {
        y *= up;
        n -= 1023;
        if (n > 1023) {
            y *= up;
            n = n - 1023 < 1023 ? n - 1023 : 1023;
        }
    } else if (n < -1022) {
        y *= down;
        n += 1022 - 53;
        if (n < -1022) {
            y *= down;
            n = n + 1022 - 53 > -1022 ? n + 1022 - 53 : -1022;
        }
    }
    return y * pg_f((unsigned long long)(0x3FF + n) << 52);
}

__device__ static double pg_exp(double x) {
    if (x != x) {
        return x;
    }
    if (x > 709.782712893384) {
        return pg_f(0x7FF0000000000000ULL);
    }
    if (x < -745.1332191019411) {
        return 0.0;
    }
    double k = round(x * pg_f(0x3FF71547652B82FEULL));
    double hi = x - k * pg_f(0x3FE62E42FEE00000ULL);
    double lo = k * pg_f(0x3DEA39EF35793C76ULL);
    double r = hi - lo;
    double rr = r * r;
    double c = r - rr * (pg_f(0x3FC555555555553EULL) +
                         rr * (pg_f(0xBF66C16C16BEBD93ULL) +
                               rr * (pg_f(0x3F11566AAF25DE2CULL) + rr * (pg_f(0xBEBBBD41C5D26BF1ULL) + rr * pg_f(0x3E66376972BEA4D0ULL)))));
    double y = 1.0 + (((r * c) / (2.0 - c) - lo) + hi);
    return pg_scale(y, (long long)k);
}

__device__ static double pg_atan_of_positive(double x) {
    const unsigned long long hi[4] = {0x3FDDAC670561BB4FULL, 0x3FE921FB54442D18ULL, 0x3FEF730BD281F69BULL, 0x3FF921FB54442D18ULL};
    const unsigned long long lo[4] = {0x3C7A2B7F222F65E2ULL, 0x3C81A62633145C07ULL, 0x3C7007887AF0CBBDULL, 0x3C91A62633145C07ULL};
    const unsigned long long at[11] = {
        0x3FD555555555550DULL, 0xBFC999999998EBC4ULL, 0x3FC24924920083FFULL, 0xBFBC71C6FE231671ULL,
        0x3FB745CDC54C206EULL, 0xBFB3B0F2AF749A6DULL, 0x3FB10D66A0D03D51ULL, 0xBFADDE2D52DEFD9AULL,
        0x3FA97B4B24760DEBULL, 0xBFA2B4442C6A6C2FULL, 0x3F90AD3AE322DA11ULL,
    };
    if (x >= pg_f(0x4410000000000000ULL)) {
        return pg_f(hi[3]);
    }
    int id;
    if (x < 0.4375) {
        id = -1;
    } else if (x < 0.6875) {
        id = 0;
        x = (2.0 * x - 1.0) / (2.0 + x);
    } else if (x < 1.1875) {
        id = 1;
        x = (x - 1.0) / (x + 1.0);
    } else if (x < 2.4375) {
        id = 2;
        x = (x - 1.5) / (1.0 + 1.5 * x);
    } else {
        id = 3;
        x = -1.0 / x;
    }
    double z = x * x;
    double w = z * z;
    double s1 = z * (pg_f(at[0]) + w * (pg_f(at[2]) + w * (pg_f(at[4]) + w * (pg_f(at[6]) + w * (pg_f(at[8]) + w * pg_f(at[10]))))));
    double s2 = w * (pg_f(at[1]) + w * (pg_f(at[3]) + w * (pg_f(at[5]) + w * (pg_f(at[7]) + w * pg_f(at[9])))));
    if (id < 0) {
        return x - x * (s1 + s2);
    }
    return pg_f(hi[id]) - ((x * (s1 + s2) - pg_f(lo[id])) - x);
}

__device__ static double pg_atan2(double y, double x) {
    if (x != x || y != y) {
        return x + y;
    }
    double sign = 1.0;
    if (y < 0.0) {
        y = -y;
        sign = -1.0;
    }
    if (x == 0.0) {
        return sign * (y == 0.0 ? 0.0 : pg_f(0x3FF921FB54442D18ULL));
    }
    double z = pg_atan_of_positive(fabs(y / x));
    if (x > 0.0) {
        return sign * z;
    }
    return sign * (pg_f(0x400921FB54442D18ULL) - (z - pg_f(0x3CA1A62633145C07ULL)));
}

// `x` beyond the dead zone, else 0 (with no gradient).
__device__ static inline double beyond(double x, double dead_zone) {
    return x > dead_zone ? x : 0.0;
}

// Closest-point parameters (s, t) of segments p1-q1 and p2-q2: frames::closest_parameters_of_segments.
__device__ static void closest_parameters(const double* p1, const double* q1, const double* p2, const double* q2,
                                          double point_m2, double* s_out, double* t_out) {
    double d1[3], d2[3], r[3];
    for (int i = 0; i < 3; ++i) {
        d1[i] = q1[i] - p1[i];
        d2[i] = q2[i] - p2[i];
        r[i] = p1[i] - p2[i];
    }
    double a = dot3(d1, d1), e = dot3(d2, d2), f = dot3(d2, r);
    double s, t;
    if (a <= point_m2 && e <= point_m2) {
        s = 0.0;
        t = 0.0;
    } else if (a <= point_m2) {
        s = 0.0;
        t = fmin(fmax(f / e, 0.0), 1.0);
    } else {
        double c = dot3(d1, r);
        if (e <= point_m2) {
            s = fmin(fmax(-c / a, 0.0), 1.0);
            t = 0.0;
        } else {
            double b = dot3(d1, d2);
            double denominator = a * e - b * b;
            s = denominator > 0.0 ? fmin(fmax((b * f - c * e) / denominator, 0.0), 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                s = fmin(fmax(-c / a, 0.0), 1.0);
                t = 0.0;
            } else if (t > 1.0) {
                s = fmin(fmax((b - c) / a, 0.0), 1.0);
                t = 1.0;
            }
        }
    }
    *s_out = s;
    *t_out = t;
}

// Adds w . dP/d(variable) for every variable, P the world end `end` (0 start, 1 end) of capsule
// `c`: every joint up to its link turns it, every earlier row's d and a move it along that row's
// z and x, and its own row stretches it as its kind says (0 along d, 1 along a, 2 a point).
__device__ static void add_end(const double* w, int link, int kind, int end, const double* point,
                               const double (*rot)[9], const double (*org)[3],
                               double* gq, double* gd, double* ga) {
    for (int j = 1; j <= link; ++j) {
        const double* R = rot[j];
        double z[3] = {R[2], R[5], R[8]};
        double v[3] = {point[0] - org[j][0], point[1] - org[j][1], point[2] - org[j][2]};
        double zxv[3] = {z[1] * v[2] - z[2] * v[1], z[2] * v[0] - z[0] * v[2], z[0] * v[1] - z[1] * v[0]};
        gq[j - 1] += dot3(w, zxv);
    }
    for (int m = 1; m < link; ++m) {
        const double* R = rot[m];
        double z[3] = {R[2], R[5], R[8]};
        double x[3] = {R[0], R[3], R[6]};
        gd[m - 1] += dot3(w, z);
        ga[m - 1] += dot3(w, x);
    }
    const double* R = rot[link];
    double z[3] = {R[2], R[5], R[8]};
    double x[3] = {R[0], R[3], R[6]};
    if (kind == 0 && end == 1) {
        gd[link - 1] += dot3(w, z);
    } else if (kind == 1) {
        gd[link - 1] += dot3(w, z);
        if (end == 1) {
            ga[link - 1] += dot3(w, x);
        }
    }
}

// Per sample: out[b] = distance, collision, then d loss / dq (n), d (n), a (n).
//
// design_static, per design: cos alpha (n), sin alpha (n), the base's rotation (9, row-major)
// and translation (3), the tool's rotation from the last link frame (9) and offset (3).
// goal_static, per goal: position (3), rotation (9, row-major), tolerance (0 pose, 1
// z-symmetric, 2 position). capsules: link and kind per capsule. candidates, grouped by checked
// pair (the model's order kept within a pair): pair, capsule, kind (0 capsule, 1 fixed segment,
// 2 floor, 3 shape), other (the capsule or the shape column); reals: the fixed segment's ends (6)
// or the floor's height (first), the radii taken off the axis distance, then a rounded
// obstacle's axis centre (3) and half length (11 in all). witness, per sample
// and shape column: distance, along, normal (3), centre (3).
extern "C" __global__ void paper_objective(
    int samples, int n, int capsule_count, int candidate_count, int pair_count, int shape_count,
    Constants k,
    const double* q, const double* d_rows, const double* a_rows,
    const int* sample_design, const int* sample_goal,
    const double* design_static, const double* goal_static,
    const int* capsule_link, const int* capsule_kind,
    const int* candidate_int, const double* candidate_real,
    const double* witness,
    double* out) {
    int b = blockIdx.x * blockDim.x + threadIdx.x;
    if (b >= samples || n > MAX_DOF || capsule_count > MAX_CAPSULES) {
        return;
    }
    int design = sample_design[b];
    const double* qs = q + (long long)b * n;
    const double* dr = d_rows + (long long)design * n;
    const double* ar = a_rows + (long long)design * n;
    const double* ds = design_static + (long long)design * (2 * n + 24);
    const double* cos_alpha = ds;
    const double* sin_alpha = ds + n;
    const double* base = ds + 2 * n;
    const double* tool = ds + 2 * n + 12;
    double* o = out + (long long)b * (2 + 3 * n);
    double* gq = o + 2;
    double* gd = gq + n;
    double* ga = gd + n;
    for (int i = 0; i < 3 * n; ++i) {
        gq[i] = 0.0;
    }

    // Link frames 0..n as rotation columns x, y, z (kept row-major in rot) and origins, as
    // tensor.rs's Frame::along, twist and turn compute them.
    double rot[MAX_DOF + 1][9];
    double org[MAX_DOF + 1][3];
    double fx[3] = {base[0], base[3], base[6]};
    double fy[3] = {base[1], base[4], base[7]};
    double fz[3] = {base[2], base[5], base[8]};
    double fo[3] = {base[9], base[10], base[11]};
    for (int i = 0; i < 9; ++i) {
        rot[0][i] = base[i];
    }
    for (int i = 0; i < 3; ++i) {
        org[0][i] = fo[i];
    }
    for (int j = 0; j < n; ++j) {
        if (j > 0) {
            for (int i = 0; i < 3; ++i) {
                fo[i] = (fo[i] + fx[i] * ar[j - 1]) + fz[i] * dr[j - 1];
            }
            double c = cos_alpha[j - 1], s = sin_alpha[j - 1];
            for (int i = 0; i < 3; ++i) {
                double y = fy[i] * c + fz[i] * s;
                double z = fz[i] * c - fy[i] * s;
                fy[i] = y;
                fz[i] = z;
            }
        }
        double c = pg_cos(qs[j]), s = pg_sin(qs[j]);
        for (int i = 0; i < 3; ++i) {
            double x = fx[i] * c + fy[i] * s;
            double y = fy[i] * c - fx[i] * s;
            fx[i] = x;
            fy[i] = y;
        }
        for (int i = 0; i < 3; ++i) {
            rot[j + 1][3 * i] = fx[i];
            rot[j + 1][3 * i + 1] = fy[i];
            rot[j + 1][3 * i + 2] = fz[i];
            org[j + 1][i] = fo[i];
        }
    }
    double last[3], tool_rot[9], tool_pos[3];
    for (int i = 0; i < 3; ++i) {
        last[i] = (fo[i] + fx[i] * ar[n - 1]) + fz[i] * dr[n - 1];
    }
    // tool rotation = [x y z] * M and position = last + [x y z] * v, each entry a sum over the
    // inner index in order, as mat_mul and mat_vec sum.
    for (int i = 0; i < 3; ++i) {
        double row[3] = {fx[i], fy[i], fz[i]};
        for (int c = 0; c < 3; ++c) {
            tool_rot[3 * i + c] = (row[0] * tool[c] + row[1] * tool[3 + c]) + row[2] * tool[6 + c];
        }
        tool_pos[i] = last[i] + ((row[0] * tool[9] + row[1] * tool[10]) + row[2] * tool[11]);
    }

    // Pose distance.
    const double* g = goal_static + (long long)sample_goal[b] * 13;
    double error[3] = {tool_pos[0] - g[0], tool_pos[1] - g[1], tool_pos[2] - g[2]};
    double error_norm = sqrt(dot3(error, error) + k.sqrt_floor);
    double position = beyond(error_norm, k.dead_zone);
    if (position > 0.0) {
        double w[3];
        for (int i = 0; i < 3; ++i) {
            w[i] = k.distance_weight * error[i] / error_norm;
        }
        // The tool point moves with every joint and every row's d and a.
        for (int j = 1; j <= n; ++j) {
            const double* R = rot[j];
            double z[3] = {R[2], R[5], R[8]};
            double v[3] = {tool_pos[0] - org[j][0], tool_pos[1] - org[j][1], tool_pos[2] - org[j][2]};
            double zxv[3] = {z[1] * v[2] - z[2] * v[1], z[2] * v[0] - z[0] * v[2], z[0] * v[1] - z[1] * v[0]};
            double x[3] = {R[0], R[3], R[6]};
            gq[j - 1] += dot3(w, zxv);
            gd[j - 1] += dot3(w, z);
            ga[j - 1] += dot3(w, x);
        }
    }
    const double* gr = g + 3;
    int mode = (int)g[12];
    double rotation = 0.0;
    double turn[3] = {0.0, 0.0, 0.0};
    if (mode == 0) {
        // error = goal^T tool; angle = atan2(|skew| / 2, (trace - 1) / 2).
        double m[9];
        for (int i = 0; i < 3; ++i) {
            for (int c = 0; c < 3; ++c) {
                m[3 * i + c] = (gr[i] * tool_rot[c] + gr[3 + i] * tool_rot[3 + c]) + gr[6 + i] * tool_rot[6 + c];
            }
        }
        double trace = (m[0] + m[4]) + m[8];
        double v[3] = {m[7] - m[5], m[2] - m[6], m[3] - m[1]};
        double length = sqrt(dot3(v, v) + k.sqrt_floor);
        double angle = beyond(pg_atan2(length * 0.5, (trace - 1.0) * 0.5), k.dead_zone);
        rotation = angle;
        if (angle > 0.0) {
            // d angle = axis . omega, the axis of tool goal^T in the world: goal v / |v|.
            for (int i = 0; i < 3; ++i) {
                turn[i] = ((gr[3 * i] * v[0] + gr[3 * i + 1] * v[1]) + gr[3 * i + 2] * v[2]) / length;
            }
        }
    } else if (mode == 1) {
        double tz[3] = {tool_rot[2], tool_rot[5], tool_rot[8]};
        double gz[3] = {gr[2], gr[5], gr[8]};
        rotation = (1.0 - dot3(gz, tz)) * 0.5;
        double cross[3] = {tz[1] * gz[2] - tz[2] * gz[1], tz[2] * gz[0] - tz[0] * gz[2], tz[0] * gz[1] - tz[1] * gz[0]};
        for (int i = 0; i < 3; ++i) {
            turn[i] = -0.5 * cross[i];
        }
    }
    double rotation_scale = k.distance_weight * k.rotation_weight;
    for (int j = 1; j <= n; ++j) {
        const double* R = rot[j];
        double z[3] = {R[2], R[5], R[8]};
        gq[j - 1] += rotation_scale * dot3(turn, z);
    }
    o[0] = position + rotation * k.rotation_weight;

    // Capsule ends in the world, as tensor.rs's collision() builds them.
    double ends[MAX_CAPSULES][6];
    for (int c = 0; c < capsule_count; ++c) {
        int link = capsule_link[c];
        const double* R = rot[link];
        double zd[3], xa[3];
        for (int i = 0; i < 3; ++i) {
            zd[i] = R[3 * i + 2] * dr[link - 1];
            xa[i] = R[3 * i] * ar[link - 1];
        }
        for (int i = 0; i < 3; ++i) {
            double start, end;
            if (capsule_kind[c] == 0) {
                start = org[link][i];
                end = org[link][i] + zd[i];
            } else if (capsule_kind[c] == 1) {
                start = org[link][i] + zd[i];
                end = start + xa[i];
            } else {
                start = org[link][i];
                end = org[link][i];
            }
            ends[c][i] = start;
            ends[c][3 + i] = end;
        }
    }

    // Each capsule's centre and half length: a pair whose candidates are all capsules or rounded
    // obstacles farther apart than the collision threshold (centres apart by more than the
    // threshold, the margin, both half lengths and the radii) costs nothing and is skipped.
    double mid[MAX_CAPSULES][4];
    for (int c = 0; c < capsule_count; ++c) {
        double axis[3];
        for (int i = 0; i < 3; ++i) {
            mid[c][i] = (ends[c][i] + ends[c][3 + i]) * 0.5;
            axis[i] = ends[c][3 + i] - ends[c][i];
        }
        mid[c][3] = sqrt(dot3(axis, axis)) * 0.5;
    }
    const double far_margin = 1e-9;

    // The closest candidate of each pair (the first strictly smallest), its cost and gradient.
    const double e1 = pg_exp(-1.0);
    const double scale = 1.0 / (1.0 - e1);
    double collision = 0.0;
    int next = 0;
    for (int pair = 0; pair < pair_count; ++pair) {
        int last = next;
        while (last < candidate_count && candidate_int[4 * last] == pair) {
            ++last;
        }
        bool far = true;
        for (int c = next; c < last && far; ++c) {
            const int* ci = candidate_int + 4 * c;
            const double* cr = candidate_real + 11 * c;
            if (ci[2] > 1) {
                far = false;
                break;
            }
            const double* m1 = mid[ci[1]];
            const double* m2 = ci[2] == 0 ? mid[ci[3]] : cr + 7;
            double apart[3] = {m1[0] - m2[0], m1[1] - m2[1], m1[2] - m2[2]};
            double reach = (((k.threshold + far_margin) + m1[3]) + m2[3]) + cr[6];
            far = dot3(apart, apart) >= reach * reach;
        }
        if (far) {
            next = last;
            continue;
        }
        int best = -1;
        double best_gap = 0.0, best_s = 0.0, best_t = 0.0;
        double best_normal[3] = {0.0, 0.0, 0.0};
        bool best_has_normal = false;
        for (; next < candidate_count && candidate_int[4 * next] == pair; ++next) {
            const int* ci = candidate_int + 4 * next;
            const double* cr = candidate_real + 11 * next;
            const double* p1 = ends[ci[1]];
            const double* q1 = ends[ci[1]] + 3;
            double gap, s = 0.0, t = 0.0, normal[3] = {0.0, 0.0, 0.0};
            bool has_normal = false;
            if (ci[2] == 2) {
                gap = (fmin(p1[2], q1[2]) - cr[6]) - cr[0];
            } else if (ci[2] == 3) {
                const double* w = witness + ((long long)b * shape_count + ci[3]) * 8;
                double point[3], offset[3];
                for (int i = 0; i < 3; ++i) {
                    point[i] = p1[i] + (q1[i] - p1[i]) * w[1];
                    offset[i] = point[i] - w[5 + i];
                }
                gap = w[0] - dot3(w + 2, offset);
                s = w[1];
                for (int i = 0; i < 3; ++i) {
                    normal[i] = w[2 + i];
                }
                has_normal = true;
            } else {
                const double* p2 = ci[2] == 0 ? ends[ci[3]] : cr;
                const double* q2 = ci[2] == 0 ? ends[ci[3]] + 3 : cr + 3;
                closest_parameters(p1, q1, p2, q2, k.point_segment_m2, &s, &t);
                double between[3];
                for (int i = 0; i < 3; ++i) {
                    between[i] = (p2[i] + (q2[i] - p2[i]) * t) - (p1[i] + (q1[i] - p1[i]) * s);
                }
                double distance = sqrt(dot3(between, between));
                if (distance >= k.meet) {
                    for (int i = 0; i < 3; ++i) {
                        normal[i] = between[i] / distance;
                    }
                    has_normal = true;
                }
                gap = distance - cr[6];
            }
            if (best < 0 || gap < best_gap) {
                best = next;
                best_gap = gap;
                best_s = s;
                best_t = t;
                best_has_normal = has_normal;
                for (int i = 0; i < 3; ++i) {
                    best_normal[i] = normal[i];
                }
            }
        }
        if (best < 0) {
            continue;
        }
        double exp_gap = pg_exp(best_gap * (-1.0 / k.threshold));
        double cost = exp_gap - e1;
        if (!(cost > 0.0)) {
            continue;
        }
        collision += cost;
        // d loss / d gap.
        double slope = k.collision_weight * scale * exp_gap * (-1.0 / k.threshold);
        const int* ci = candidate_int + 4 * best;
        int capsule = ci[1];
        int link = capsule_link[capsule], kind = capsule_kind[capsule];
        if (ci[2] == 2) {
            int lower = ends[capsule][5] < ends[capsule][2] ? 1 : 0;
            double w[3] = {0.0, 0.0, slope};
            add_end(w, link, kind, lower, ends[capsule] + 3 * lower, rot, org, gq, gd, ga);
            continue;
        }
        if (!best_has_normal) {
            continue;
        }
        // The gap moves by -(1 - s) n, -s n with the first capsule's ends, (1 - t) n, t n with
        // the other's.
        double w[3];
        for (int i = 0; i < 3; ++i) {
            w[i] = -slope * (1.0 - best_s) * best_normal[i];
        }
        add_end(w, link, kind, 0, ends[capsule], rot, org, gq, gd, ga);
        for (int i = 0; i < 3; ++i) {
            w[i] = -slope * best_s * best_normal[i];
        }
        add_end(w, link, kind, 1, ends[capsule] + 3, rot, org, gq, gd, ga);
        if (ci[2] == 0) {
            int other = ci[3];
            int link_b = capsule_link[other], kind_b = capsule_kind[other];
            for (int i = 0; i < 3; ++i) {
                w[i] = slope * (1.0 - best_t) * best_normal[i];
            }
            add_end(w, link_b, kind_b, 0, ends[other], rot, org, gq, gd, ga);
            for (int i = 0; i < 3; ++i) {
                w[i] = slope * best_t * best_normal[i];
            }
            add_end(w, link_b, kind_b, 1, ends[other] + 3, rot, org, gq, gd, ga);
        }
    }
    o[1] = collision * scale;
}

// The rest of optimize()'s step on the device, so that a run keeps every step there (one launch
// each, no copy until the end): the same operations in the same order as sim/optimize/mod.rs
// (`Adam::step`, `project`, `design_objective`, `Best::keep`), so the run is the CPU's, bit for bit.
// Rows of `out` are the objective kernel's: distance, collision, then d loss / dq, dd, da (n each).

struct Step {
    int n, samples, designs, goals;
    double beta1, beta2, epsilon, joint_rate, design_rate;
    double bias1, bias2;          // 1 - beta^step, computed on the host as the CPU computes them
    double hardware_weight, distance_weight, collision_weight;
    double max_length, economic_lower, economic_upper;
};

__device__ static inline double pg_clamp(double v, double lower, double upper) {
    return v < lower ? lower : (v > upper ? upper : v);
}

__device__ static inline double pg_signum(double v) {
    return v != v ? v : copysign(1.0, v);
}

__device__ static inline void pg_adam(double* value, double* first, double* second, double g, double rate, const Step& s) {
    *first = s.beta1 * *first + (1.0 - s.beta1) * g;
    *second = s.beta2 * *second + (1.0 - s.beta2) * g * g;
    double m = *first / s.bias1, v = *second / s.bias2;
    *value -= rate * m / (sqrt(v) + s.epsilon);
}

// Per sample: Adam on its joints, then each into its joint's limits.
extern "C" __global__ void joint_step(Step s, double* q, double* first, double* second, const double* out,
                                      const int* sample_design, const double* limits) {
    int b = blockIdx.x * blockDim.x + threadIdx.x;
    if (b >= s.samples) {
        return;
    }
    const double* grad_q = out + (long long)b * (2 + 3 * s.n) + 2;
    const double* lim = limits + (long long)sample_design[b] * s.n * 2;
    for (int j = 0; j < s.n; ++j) {
        long long i = (long long)b * s.n + j;
        pg_adam(&q[i], &first[i], &second[i], grad_q[j], s.joint_rate, s);
        q[i] = pg_clamp(q[i], lim[2 * j], lim[2 * j + 1]);
    }
}

// Per design: the gradient of its objective (its goals' chosen samples, in sample order, and the
// hardware cost's signs), Adam on its free d and a, then the projection by its mode.
extern "C" __global__ void design_step(Step s, double* d, double* a, double* first_d, double* second_d,
                                       double* first_a, double* second_a, const double* out, const int* chosen,
                                       const int* design_offsets, const int* design_samples, const int* free_d,
                                       const int* free_a, const int* economic) {
    int k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= s.designs) {
        return;
    }
    int width = 2 + 3 * s.n;
    for (int j = 0; j < s.n; ++j) {
        double gd = 0.0, ga = 0.0;
        for (int at = design_offsets[k]; at < design_offsets[k + 1]; ++at) {
            int b = design_samples[at];
            if (chosen[b]) {
                gd += out[(long long)b * width + 2 + s.n + j];
                ga += out[(long long)b * width + 2 + 2 * s.n + j];
            }
        }
        long long i = (long long)k * s.n + j;
        gd += s.hardware_weight * pg_signum(d[i]);
        ga += s.hardware_weight * pg_signum(a[i]);
        if (free_d[i]) {
            pg_adam(&d[i], &first_d[i], &second_d[i], gd, s.design_rate, s);
        }
        if (free_a[i]) {
            pg_adam(&a[i], &first_a[i], &second_a[i], ga, s.design_rate, s);
        }
        double* values[2] = {&d[i], &a[i]};
        for (int v = 0; v < 2; ++v) {
            double x = *values[v];
            *values[v] = economic[k] && x != 0.0 ? pg_signum(x) * pg_clamp(fabs(x), s.economic_lower, s.economic_upper)
                                                 : pg_clamp(x, -s.max_length, s.max_length);
        }
    }
}

// Per design: its objective (the hardware cost, then each goal's best start in goal order, the
// lowest index among equals) and which samples are chosen.
extern "C" __global__ void choose(Step s, const double* d, const double* a, const double* out, int* chosen,
                                  double* objective, const int* slot_offsets, const int* slot_samples) {
    int k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= s.designs) {
        return;
    }
    int width = 2 + 3 * s.n;
    double hardware = -0.0;
    for (int j = 0; j < s.n; ++j) {
        hardware += fabs(d[(long long)k * s.n + j]);
    }
    for (int j = 0; j < s.n; ++j) {
        hardware += fabs(a[(long long)k * s.n + j]);
    }
    double value = s.hardware_weight * hardware;
    for (int g = 0; g < s.goals; ++g) {
        int slot = k * s.goals + g;
        int best = -1;
        double best_loss = 0.0;
        for (int at = slot_offsets[slot]; at < slot_offsets[slot + 1]; ++at) {
            int b = slot_samples[at];
            chosen[b] = 0;
            double loss = s.distance_weight * out[(long long)b * width] + s.collision_weight * out[(long long)b * width + 1];
            if (best < 0 || loss < best_loss) {
                best = b;
                best_loss = loss;
            }
        }
        if (best >= 0) {
            chosen[best] = 1;
            value += best_loss;
        }
    }
    objective[k] = value;
}

// Per design: its rows kept where its objective beats its best (a number beats a NaN).
extern "C" __global__ void keep(Step s, int step, const double* objective, double* best_objective, int* best_step,
                                const double* q, const double* d, const double* a, const double* out, double* best_q,
                                double* best_d, double* best_a, double* best_out, const int* design_offsets,
                                const int* design_samples) {
    int k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= s.designs) {
        return;
    }
    double v = objective[k], kept = best_objective[k];
    bool better = v < kept || (kept != kept && v == v);
    if (!better) {
        return;
    }
    best_objective[k] = v;
    best_step[k] = step;
    for (int j = 0; j < s.n; ++j) {
        best_d[(long long)k * s.n + j] = d[(long long)k * s.n + j];
        best_a[(long long)k * s.n + j] = a[(long long)k * s.n + j];
    }
    int width = 2 + 3 * s.n;
    for (int at = design_offsets[k]; at < design_offsets[k + 1]; ++at) {
        long long b = design_samples[at];
        for (int j = 0; j < s.n; ++j) {
            best_q[b * s.n + j] = q[b * s.n + j];
        }
        for (int i = 0; i < width; ++i) {
            best_out[b * width + i] = out[b * width + i];
        }
    }
}
