/* Shared by the two window drivers (mhe_plain.c, mhe_window.c) of wheelload_mhe.c. */

/* The fallback filter (appended after the driver: the linked KF, or the held estimate). */
static void kf_reset(wheelload_mhe_state *mhe);
/* its covariance [N^2] before the sample, 4 x 4 */
static void kf_covariance(const wheelload_mhe_state *mhe, double *P);
static void kf_step(wheelload_mhe_state *mhe, const double *u, double dt, double *x, double *std);
static void kf_held(const wheelload_mhe_state *mhe, const double *u, double dt, const double *held,
                    double *std, double *residual);
/* Arrival weight c s^2 Pi^-1 of a window starting at the sample (first: the log's first). */
static void arrival_weight(bool first, const double *P, double dt, double *weight);

/* Gauss-Jordan inverse with partial pivoting of the n x n matrix a (overwritten). */
static void invert(double *a, int n, double *inverse) {
    for (int r = 0; r < n; ++r) {
        for (int c = 0; c < n; ++c) {
            inverse[r * n + c] = r == c;
        }
    }
    for (int c = 0; c < n; ++c) {
        int p = c;
        for (int r = c + 1; r < n; ++r) {
            if (fabs(a[r * n + c]) > fabs(a[p * n + c])) {
                p = r;
            }
        }
        for (int e = 0; e < n; ++e) {
            double t = a[c * n + e];
            a[c * n + e] = a[p * n + e];
            a[p * n + e] = t;
            t = inverse[c * n + e];
            inverse[c * n + e] = inverse[p * n + e];
            inverse[p * n + e] = t;
        }
        double pivot = a[c * n + c];
        for (int e = 0; e < n; ++e) {
            a[c * n + e] /= pivot;
            inverse[c * n + e] /= pivot;
        }
        for (int r = 0; r < n; ++r) {
            if (r == c) {
                continue;
            }
            double f = a[r * n + c];
            for (int e = 0; e < n; ++e) {
                a[r * n + e] -= f * a[c * n + e];
                inverse[r * n + e] -= f * inverse[c * n + e];
            }
        }
    }
}

/* true when every load is finite and |x| <= LOAD_LIMIT (NaN fails), as plausible_loads in Python. */
static bool plausible_loads(const double *x) {
    for (int i = 0; i < 4; ++i) {
        if (!(fabs(x[i]) <= LOAD_LIMIT)) {
            return false;
        }
    }
    return true;
}

/* The loads of a sample whose QP is not solved: the filter's, clipped to the bounds; the held
   (last) estimate when the filter's is not finite or beyond LOAD_LIMIT. */
static void fallback_loads(const double *filtered, const double *held, double *x) {
    const double *source = plausible_loads(filtered) ? filtered : held;
    for (int i = 0; i < 4; ++i) {
        x[i] = fmin(fmax(source[i], LOW_LOAD), HIGH_LOAD);
    }
}

/* true when the QP data can be handed to OSQP: Hessian values and linear term finite, no bound
   NaN (the caller's bounds are clamped to OSQP_INFTY); else the sample is not solved. */
static bool finite_data(const OSQPFloat *Px, int nnz, const OSQPFloat *q, const OSQPFloat *l,
                       const OSQPFloat *u, int n, bool bounds) {
    for (int i = 0; i < nnz; ++i) {
        if (!isfinite((double)Px[i])) {
            return false;
        }
    }
    for (int i = 0; i < n; ++i) {
        if (!isfinite((double)q[i])) {
            return false;
        }
        if (bounds && (isnan((double)l[i]) || isnan((double)u[i]))) {
            return false;
        }
    }
    return true;
}

/* Loads [N] from one sample's QP variables (block: its W load variables first), or false if out of
   [lower, upper] by more than ten times OSQP's primal tolerance (as the Python MHE's check) or
   not plausible_loads; clipped to the bounds. xp: the sample's particular solution (hard
   constraint only); a collapsed warp interval (lower == upper: no bounded loads satisfy the
   equilibrium) gives its loads clipped to the bounds. */
static bool clipped_loads(const OSQPFloat *block, const double *lower, const double *upper,
                         const double *xp, double *loads) {
    double value[W], largest = 1.0;
    for (int a = 0; a < W; ++a) {
        value[a] = (double)block[a];
        largest = fmax(largest, fabs(value[a]));
    }
    double tolerance = 10.0 * (EPS_ABS + EPS_REL * largest);
    for (int a = 0; a < W; ++a) {
        if (value[a] < lower[a] - tolerance || value[a] > upper[a] + tolerance) {
            return false;
        }
        value[a] = fmin(fmax(value[a], lower[a]), upper[a]);
    }
#if HARD
    double x[4], big = 1.0;
    for (int i = 0; i < 4; ++i) {
        x[i] = xp[i] + NULL_VECTOR[i] * (value[0] * LOAD_SCALE);
        big = fmax(big, fabs(x[i]));
    }
    tolerance = lower[0] == upper[0] ? INFINITY : 10.0 * (1e-9 + 1e-12 * big);
    for (int i = 0; i < 4; ++i) {
        if (x[i] < LOW_LOAD - tolerance || x[i] > HIGH_LOAD + tolerance) {
            return false;
        }
        loads[i] = fmin(fmax(x[i], LOW_LOAD), HIGH_LOAD);
    }
#else
    (void)xp;
    for (int i = 0; i < 4; ++i) {
        loads[i] = value[i] * LOAD_SCALE;
    }
#endif
    return plausible_loads(loads);
}

