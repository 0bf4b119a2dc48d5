/* The embedded MHE with quadratic losses (wheelload.estimators.mhe.estimator): the window of per-sample
 * terms of wheelload_mhe_terms, the Hessian values in OSQP's CSC order (loaded only when they
 * change), q, l, u, a warm start from the shifted previous solution, and one solve. */

/* The window, oldest sample first: the terms of wheelload_mhe_terms (QP units). */
static double HB[N][W * W], G[N][W], LINK[N], DRIFT[N], XP[N][4], LO[N][W], HI[N][W];
static double BW[N][3];  /* each sample's equilibrium right-hand side b */
static double KFX[N][4]; /* the fallback's estimate of each sample */
static double ARR[N][16]; /* arrival weight c s^2 Pi^-1 of a window starting there */
static double HIST[N][4];
static OSQPFloat XW[NX], YW[NY], Q[NX], L[NX + 1], U[NX + 1], PX[NNZ]; /* OSQP's type */
static double VALUES[N * W * W + (N - 1) * W]; /* diagonal blocks, then couplings */
static double FALLBACK[4];
static long K = 0;

void wheelload_mhe_reset(void) {
    K = 0;
    memset(XW, 0, sizeof XW);
    memset(YW, 0, sizeof YW);
    memset(HB, 0, sizeof HB);
    memset(G, 0, sizeof G);
    memset(LINK, 0, sizeof LINK);
    memset(DRIFT, 0, sizeof DRIFT);
    memset(XP, 0, sizeof XP);
    memset(LO, 0, sizeof LO);
    memset(HI, 0, sizeof HI);
    memset(BW, 0, sizeof BW);
    memset(ARR, 0, sizeof ARR);
    for (int j = 0; j < N; ++j) {
        for (int a = 0; a < W; ++a) HB[j][a * W + a] = 1.0; /* inert samples before the log */
        memcpy(HIST[j], X0, sizeof X0);
        memcpy(KFX[j], X0, sizeof X0);
    }
@@ reset_filter
}

static void shift(double *rows, const double *value, int width) {
    memmove(rows, rows + width, sizeof(double) * (size_t)(width * (N - 1)));
    memcpy(rows + width * (N - 1), value, sizeof(double) * (size_t)width);
}

/* Upper-triangular Hessian values in OSQP's CSC order; 1 if they differ from the loaded. */
static int hessian(int j0, const double *arrival) {
    double diagonal[N];
    for (int j = 0; j < N; ++j)
        diagonal[j] = (j > 0 ? LINK[j] : 0.0) + (j < N - 1 ? LINK[j + 1] : 0.0);
#if HARD
    for (int j = 0; j < N; ++j) VALUES[j] = HB[j][0] + diagonal[j];
    double warp = 0.0;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) warp += NULL_VECTOR[r] * arrival[r * 4 + c] * NULL_VECTOR[c];
    VALUES[j0] += warp;
    for (int j = 1; j < N; ++j) VALUES[N + j - 1] = -LINK[j];
#else
    for (int j = 0; j < N; ++j)
        for (int e = 0; e < 16; ++e)
            VALUES[j * 16 + e] = HB[j][e] + (e % 5 == 0 ? diagonal[j] : 0.0)
                                 + (j == j0 ? arrival[e] : 0.0);
    for (int j = 1; j < N; ++j)
        for (int a = 0; a < 4; ++a) VALUES[N * 16 + (j - 1) * 4 + a] = -LINK[j];
#endif
    int changed = K == 0;
    for (int i = 0; i < NNZ; ++i) {
        OSQPFloat value = (OSQPFloat)VALUES[ORDER[i]];
        if (value != PX[i]) changed = 1;
        PX[i] = value;
    }
    return changed;
}

/* Loads [N] of window sample j (clipped_loads). */
static int checked(int j, double *loads) {
    return clipped_loads(XW + j * W, LO[j], HI[j], XP[j], loads);
}

int wheelload_mhe_step(const double *u, double dt, wheelload_mhe_output *out) {
    double u0[N_INPUTS], valid[N_INPUTS], cost = COST, previous_P[16];
    memset(out, 0, sizeof *out);
@@ interval_and_inputs
    double std[4];
    kf_step(u, dt, FALLBACK, std);
    double h[W * W], g[W], link, xp[4], lo[W], hi[W], b[3], used[N_USED], arrival[16];
    wheelload_mhe_terms(u0, valid, &dt, FALLBACK, P_VECTOR, TUNING, &cost, h, g, &link, xp, lo,
                        hi, b, used);
    for (int i = 0; i < N_USED; ++i) out->flags |= used[i] < 0.5 ? UPDATE_FLAGS[i] : 0u;
    if (K == 0) link = 0.0; /* the log's first sample: the arrival cost instead */
    double drift = 0.0;
#if HARD
    for (int r = 0; r < 4; ++r) drift += NULL_VECTOR[r] * (xp[r] - XP[N - 1][r]);
    drift *= link / LOAD_SCALE;
#endif
    arrival_weight(K == 0, previous_P, dt, arrival);
    shift(HB[0], h, W * W); shift(G[0], g, W); shift(LINK, &link, 1); shift(DRIFT, &drift, 1);
    shift(XP[0], xp, 4); shift(LO[0], lo, W); shift(HI[0], hi, W); shift(BW[0], b, 3);
    shift(KFX[0], FALLBACK, 4); shift(ARR[0], arrival, 16);
    int j0 = K < N - 1 ? (int)(N - 1 - K) : 0;
    memmove(XW, XW + W, sizeof(OSQPFloat) * (NX - W));
#if HAS_Y
    memmove(YW, YW + W, sizeof(OSQPFloat) * (NY - W));
#endif
    int data = 0;
    for (int j = j0; j < N; ++j)
        for (int e = 0; e < W * W; ++e) data |= HB[j][e] != 0.0;
    int status = 1;
    if (!data) { /* no data term in the window: the last estimate carried by the random walk */
        double solution[N][W];
        for (int j = 0; j < N; ++j)
            for (int a = 0; a < W; ++a) solution[j][a] = (double)XW[j * W + a];
#if HARD
        double Wn[4], nWn = 0.0, num = 0.0;
        for (int r = 0; r < 4; ++r) {
            Wn[r] = 0.0;
            for (int c = 0; c < 4; ++c) Wn[r] += ARR[j0][r * 4 + c] * NULL_VECTOR[c];
            nWn += NULL_VECTOR[r] * Wn[r];
        }
        for (int r = 0; r < 4; ++r) num += Wn[r] * (HIST[N - 1][r] - XP[j0][r]);
        double omega = num / nWn / LOAD_SCALE;
        for (int j = j0; j < N; ++j) {
            if (j > j0) {
                double step = 0.0;
                for (int r = 0; r < 4; ++r) step += NULL_VECTOR[r] * (XP[j][r] - XP[j - 1][r]);
                omega -= step / LOAD_SCALE;
            }
            solution[j][0] = omega;
        }
#else
        for (int j = j0; j < N; ++j)
            for (int a = 0; a < 4; ++a) solution[j][a] = HIST[N - 1][a] / LOAD_SCALE;
#endif
        for (int j = 0; j < N; ++j)
            for (int a = 0; a < W; ++a) {
                double v = solution[j][a];
                if (j >= j0) v = fmin(fmax(v, LO[j][a]), HI[j][a]);
                XW[j * W + a] = (OSQPFloat)v;
            }
    } else {
        int changed = hessian(j0, ARR[j0]);
        const double *prior = HIST[0];
        for (int j = 0; j < N; ++j)
            for (int a = 0; a < W; ++a) {
                Q[j * W + a] = (OSQPFloat)G[j][a];
                L[j * W + a] = (OSQPFloat)fmax(LO[j][a], -(double)OSQP_INFTY);
                U[j * W + a] = (OSQPFloat)fmin(HI[j][a], (double)OSQP_INFTY);
            }
        const double *weight = ARR[j0];
#if HARD
        for (int j = 1; j < N; ++j) {
            Q[j] = (OSQPFloat)((double)Q[j] + DRIFT[j]);
            Q[j - 1] = (OSQPFloat)((double)Q[j - 1] - DRIFT[j]);
        }
        double nw = 0.0;
        for (int r = 0; r < 4; ++r) {
            double row = 0.0;
            for (int c = 0; c < 4; ++c) row += weight[r * 4 + c] * (XP[j0][c] - prior[c]);
            nw += NULL_VECTOR[r] * row;
        }
        Q[j0] = (OSQPFloat)((double)Q[j0] + nw / LOAD_SCALE);
#else
        for (int r = 0; r < 4; ++r) {
            double row = 0.0;
            for (int c = 0; c < 4; ++c) row += weight[r * 4 + c] * prior[c];
            Q[j0 * W + r] = (OSQPFloat)((double)Q[j0 * W + r] - row / LOAD_SCALE);
        }
#endif
        if (finite_data(PX, NNZ, Q, L, U, NX, HAS_Y)) {
            if (changed)
                osqp_update_data_mat(&wheelload_mhe_solver, PX, OSQP_NULL, NNZ, OSQP_NULL,
                                     OSQP_NULL, 0);
            osqp_update_data_vec(&wheelload_mhe_solver, Q, HAS_Y ? L : OSQP_NULL,
                                 HAS_Y ? U : OSQP_NULL);
#if HAS_Y
            osqp_warm_start(&wheelload_mhe_solver, XW, YW);
#else
            osqp_warm_start(&wheelload_mhe_solver, XW, OSQP_NULL);
#endif
@@ solve
        if (status == 1) {
            memcpy(XW, wheelload_mhe_solver.solution->x, sizeof XW);
#if HAS_Y
            memcpy(YW, wheelload_mhe_solver.solution->y, sizeof YW);
#endif
        }
    }
    double x[4];
    int failed = status != 1 || !checked(N - 1, x);
    if (failed) fallback_loads(FALLBACK, HIST[N - 1], x);
    shift(HIST[0], x, 4);
    ++K;
    /* the output: the window's estimate of sample k - LAG */
    if (LAG == 0 || failed) {
        memcpy(out->loads, x, sizeof x);
    } else if (!checked(N - 1 - LAG, out->loads)) {
        fallback_loads(KFX[N - 1 - LAG], HIST[N - 1], out->loads);
    }
    for (int r = 0; r < 3; ++r) {
        out->residual[r] = BW[N - 1 - LAG][r];
        for (int c = 0; c < 4; ++c) out->residual[r] -= A_MATRIX[r * 4 + c] * out->loads[c];
    }
    memcpy(out->std, std, sizeof std);
    out->fallback = failed;
    return status;
}
