/* The embedded MHE with quadratic losses (wheelload.estimators.mhe.estimator): the window of
 * per-sample terms of wheelload_mhe_terms, the Hessian values in OSQP's CSC order (loaded only
 * when they change), q, l, u, a warm start from the shifted previous solution, and one solve.
 * Every value that lives from one sample to the next is in the caller's wheelload_mhe_state
 * (mhe->, the members of wheelload_mhe_state.h), its solver included. */

void wheelload_mhe_reset(wheelload_mhe_state *mhe) {
    mhe->K = 0;
    (void)memset(mhe->XW, 0, sizeof mhe->XW);
    (void)memset(mhe->YW, 0, sizeof mhe->YW);
    (void)memset(mhe->HB, 0, sizeof mhe->HB);
    (void)memset(mhe->G, 0, sizeof mhe->G);
    (void)memset(mhe->LINK, 0, sizeof mhe->LINK);
    (void)memset(mhe->DRIFT, 0, sizeof mhe->DRIFT);
    (void)memset(mhe->XP, 0, sizeof mhe->XP);
    (void)memset(mhe->LO, 0, sizeof mhe->LO);
    (void)memset(mhe->HI, 0, sizeof mhe->HI);
    (void)memset(mhe->BW, 0, sizeof mhe->BW);
    (void)memset(mhe->ARR, 0, sizeof mhe->ARR);
    for (int j = 0; j < N; ++j) {
        for (int a = 0; a < W; ++a) {
            mhe->HB[j][a * W + a] = 1.0; /* inert samples before the log */
        }
        (void)memcpy(mhe->HIST[j], X0, sizeof X0);
        (void)memcpy(mhe->KFX[j], X0, sizeof X0);
    }
@@ reset_filter
}

static void shift(double *rows, const double *value, int width) {
    (void)memmove(rows, rows + width, sizeof(double) * (size_t)width * ((size_t)N - 1u));
    (void)memcpy(rows + width * (N - 1), value, sizeof(double) * (size_t)width);
}

/* Upper-triangular Hessian values in OSQP's CSC order; 1 if they differ from the loaded. */
static bool hessian(wheelload_mhe_state *mhe, int j0, const double *arrival) {
    double diagonal[N];
    for (int j = 0; j < N; ++j) {
        diagonal[j] = (j > 0 ? mhe->LINK[j] : 0.0) + (j < N - 1 ? mhe->LINK[j + 1] : 0.0);
    }
#if HARD
    for (int j = 0; j < N; ++j) {
        mhe->VALUES[j] = mhe->HB[j][0] + diagonal[j];
    }
    double warp = 0.0;
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            warp += NULL_VECTOR[r] * arrival[r * 4 + c] * NULL_VECTOR[c];
        }
    }
    mhe->VALUES[j0] += warp;
    for (int j = 1; j < N; ++j) {
        mhe->VALUES[N + j - 1] = -mhe->LINK[j];
    }
#else
    for (int j = 0; j < N; ++j) {
        for (int e = 0; e < 16; ++e) {
            mhe->VALUES[j * 16 + e] = mhe->HB[j][e] + (e % 5 == 0 ? diagonal[j] : 0.0)
                                      + (j == j0 ? arrival[e] : 0.0);
        }
    }
    for (int j = 1; j < N; ++j) {
        for (int a = 0; a < 4; ++a) {
            mhe->VALUES[N * 16 + (j - 1) * 4 + a] = -mhe->LINK[j];
        }
    }
#endif
    bool changed = mhe->K == 0;
    for (int i = 0; i < NNZ; ++i) {
        OSQPFloat value = (OSQPFloat)mhe->VALUES[ORDER[i]];
        if (value != mhe->PX[i]) {
            changed = true;
        }
        mhe->PX[i] = value;
    }
    return changed;
}

/* Loads [N] of window sample j (clipped_loads). */
static bool checked(const wheelload_mhe_state *mhe, int j, double *loads) {
    return clipped_loads(mhe->XW + j * W, mhe->LO[j], mhe->HI[j], mhe->XP[j], loads);
}

int wheelload_mhe_step(wheelload_mhe_state *mhe, const double *u, double dt,
                      wheelload_mhe_output *out) {
    double u0[N_INPUTS], valid[N_INPUTS], cost = COST, previous_P[16];
    (void)memset(out, 0, sizeof *out);
@@ interval_and_inputs
    double std[4];
    kf_step(mhe, u, dt, mhe->FALLBACK, std);
    double h[W * W], g[W], link, xp[4], lo[W], hi[W], b[3], used[N_USED], arrival[16];
    wheelload_mhe_terms(u0, valid, &dt, mhe->FALLBACK, P_VECTOR, TUNING, &cost, h, g, &link, xp,
                        lo, hi, b, used);
    for (int i = 0; i < N_USED; ++i) {
        out->flags |= used[i] < 0.5 ? UPDATE_FLAGS[i] : 0u;
    }
    if (mhe->K == 0) {
        link = 0.0; /* the log's first sample: the arrival cost instead */
    }
    double drift = 0.0;
#if HARD
    for (int r = 0; r < 4; ++r) {
        drift += NULL_VECTOR[r] * (xp[r] - mhe->XP[N - 1][r]);
    }
    drift *= link / LOAD_SCALE;
#endif
    arrival_weight(mhe->K == 0, previous_P, dt, arrival);
    shift(mhe->HB[0], h, W * W);
    shift(mhe->G[0], g, W);
    shift(mhe->LINK, &link, 1);
    shift(mhe->DRIFT, &drift, 1);
    shift(mhe->XP[0], xp, 4);
    shift(mhe->LO[0], lo, W);
    shift(mhe->HI[0], hi, W);
    shift(mhe->BW[0], b, 3);
    shift(mhe->KFX[0], mhe->FALLBACK, 4);
    shift(mhe->ARR[0], arrival, 16);
    int j0 = mhe->K < N - 1 ? (int)(N - 1 - mhe->K) : 0;
    (void)memmove(mhe->XW, mhe->XW + W, sizeof(OSQPFloat) * ((size_t)NX - (size_t)W));
#if HAS_Y
    (void)memmove(mhe->YW, mhe->YW + W, sizeof(OSQPFloat) * ((size_t)NY - (size_t)W));
#endif
    bool data = false;
    for (int j = j0; j < N; ++j) {
        for (int e = 0; e < W * W; ++e) {
            data = data || mhe->HB[j][e] != 0.0;
        }
    }
    int status = 1;
    if (!data) { /* no data term in the window: the last estimate carried by the random walk */
        double solution[N][W];
        for (int j = 0; j < N; ++j) {
            for (int a = 0; a < W; ++a) {
                solution[j][a] = (double)mhe->XW[j * W + a];
            }
        }
#if HARD
        double Wn[4], nWn = 0.0, num = 0.0;
        for (int r = 0; r < 4; ++r) {
            Wn[r] = 0.0;
            for (int c = 0; c < 4; ++c) {
                Wn[r] += mhe->ARR[j0][r * 4 + c] * NULL_VECTOR[c];
            }
            nWn += NULL_VECTOR[r] * Wn[r];
        }
        for (int r = 0; r < 4; ++r) {
            num += Wn[r] * (mhe->HIST[N - 1][r] - mhe->XP[j0][r]);
        }
        double omega = num / nWn / LOAD_SCALE;
        for (int j = j0; j < N; ++j) {
            if (j > j0) {
                double step = 0.0;
                for (int r = 0; r < 4; ++r) {
                    step += NULL_VECTOR[r] * (mhe->XP[j][r] - mhe->XP[j - 1][r]);
                }
                omega -= step / LOAD_SCALE;
            }
            solution[j][0] = omega;
        }
#else
        for (int j = j0; j < N; ++j) {
            for (int a = 0; a < 4; ++a) {
                solution[j][a] = mhe->HIST[N - 1][a] / LOAD_SCALE;
            }
        }
#endif
        for (int j = 0; j < N; ++j) {
            for (int a = 0; a < W; ++a) {
                double v = solution[j][a];
                if (j >= j0) {
                    v = fmin(fmax(v, mhe->LO[j][a]), mhe->HI[j][a]);
                }
                mhe->XW[j * W + a] = (OSQPFloat)v;
            }
        }
    } else {
        bool changed = hessian(mhe, j0, mhe->ARR[j0]);
        const double *prior = mhe->HIST[0];
        for (int j = 0; j < N; ++j) {
            for (int a = 0; a < W; ++a) {
                mhe->Q[j * W + a] = (OSQPFloat)mhe->G[j][a];
                mhe->L[j * W + a] = (OSQPFloat)fmax(mhe->LO[j][a], -(double)OSQP_INFTY);
                mhe->U[j * W + a] = (OSQPFloat)fmin(mhe->HI[j][a], (double)OSQP_INFTY);
            }
        }
        const double *weight = mhe->ARR[j0];
#if HARD
        for (int j = 1; j < N; ++j) {
            mhe->Q[j] = (OSQPFloat)((double)mhe->Q[j] + mhe->DRIFT[j]);
            mhe->Q[j - 1] = (OSQPFloat)((double)mhe->Q[j - 1] - mhe->DRIFT[j]);
        }
        double nw = 0.0;
        for (int r = 0; r < 4; ++r) {
            double row = 0.0;
            for (int c = 0; c < 4; ++c) {
                row += weight[r * 4 + c] * (mhe->XP[j0][c] - prior[c]);
            }
            nw += NULL_VECTOR[r] * row;
        }
        mhe->Q[j0] = (OSQPFloat)((double)mhe->Q[j0] + nw / LOAD_SCALE);
#else
        for (int r = 0; r < 4; ++r) {
            double row = 0.0;
            for (int c = 0; c < 4; ++c) {
                row += weight[r * 4 + c] * prior[c];
            }
            mhe->Q[j0 * W + r] = (OSQPFloat)((double)mhe->Q[j0 * W + r] - row / LOAD_SCALE);
        }
#endif
        if (finite_data(mhe->PX, NNZ, mhe->Q, mhe->L, mhe->U, NX, HAS_Y != 0)) {
            if (changed) {
                (void)osqp_update_data_mat(&mhe->osqp.solver, mhe->PX, NULL, NNZ, NULL,
                                     NULL, 0);
            }
            (void)osqp_update_data_vec(&mhe->osqp.solver, mhe->Q, HAS_Y ? mhe->L : NULL,
                                 HAS_Y ? mhe->U : NULL);
#if HAS_Y
            (void)osqp_warm_start(&mhe->osqp.solver, mhe->XW, mhe->YW);
#else
            (void)osqp_warm_start(&mhe->osqp.solver, mhe->XW, NULL);
#endif
@@ solve
        if (status == 1) {
            (void)memcpy(mhe->XW, mhe->osqp.solver.solution->x, sizeof mhe->XW);
#if HAS_Y
            (void)memcpy(mhe->YW, mhe->osqp.solver.solution->y, sizeof mhe->YW);
#endif
        }
    }
    double x[4];
    bool failed = status != 1 || !checked(mhe, N - 1, x);
    if (failed) {
        fallback_loads(mhe->FALLBACK, mhe->HIST[N - 1], x);
    }
    shift(mhe->HIST[0], x, 4);
    ++mhe->K;
    /* the output: the window's estimate of sample k - LAG (window sample OUTPUT_SAMPLE) */
#if LAG == 0
    (void)memcpy(out->loads, x, sizeof x);
#else
    if (failed) {
        (void)memcpy(out->loads, x, sizeof x);
    } else if (!checked(mhe, OUTPUT_SAMPLE, out->loads)) {
        fallback_loads(mhe->KFX[OUTPUT_SAMPLE], mhe->HIST[N - 1], out->loads);
    } else {
        /* the window's estimate of sample k - LAG, within its bounds */
    }
#endif
    for (int r = 0; r < 3; ++r) {
        out->residual[r] = mhe->BW[OUTPUT_SAMPLE][r];
        for (int c = 0; c < 4; ++c) {
            out->residual[r] -= A_MATRIX[r * 4 + c] * out->loads[c];
        }
    }
    (void)memcpy(out->std, std, sizeof std);
    out->fallback = failed;
    return status;
}
