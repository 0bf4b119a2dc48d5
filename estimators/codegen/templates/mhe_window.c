/* The embedded MHE with robust losses, bias states and lagged output (wheelload.estimators.
 * mhe.window): one QP per sample on OSQP's embedded solver, set up once with the fixed
 * upper-triangular pattern of the Python MHE's window (COLUMN_START, ROW_INDEX: OSQP's CSC
 * column starts and row indices); the Hessian is assembled into its values at that pattern
 * (HV, CSC order), never as a dense matrix.
 *
 * Variables (QP units): per sample a block of WIDTH entries, the W load variables (kN, or the
 * warp amplitude in kN for the hard constraint) then the auxiliaries e+, e- of the robust
 * suspension rows (NS each) and equilibrium rows (NC each), in sigma; then the NB bias states
 * (travel offsets in mm along TRAVEL_BASIS, ax/ay biases in m/s^2). Each row i of sample j,
 * rho = sqrt(mask dt / r) r_i (the CasADi rows of wheelload_mhe_residual_rows), costs
 * kappa/2 (rho - e)^2 + mu |e| (quadratic: 1/2 rho^2). The bias arrival weight (information)
 * loses q_b dt of variance per sample and gains the Schur complement of each sample that leaves
 * the window, rows weighted by the loss's effective (IRLS) weight. Every value that lives from
 * one sample to the next is in the caller's wheelload_mhe_state (mhe->, the members of
 * wheelload_mhe_state.h), its solver included. */

#define NM (W + NB) /* what a data row acts on: the loads, then the biases */

/* A sample of the window (wheelload_mhe_state.h). */
typedef wheelload_mhe_sample sample_t;

void wheelload_mhe_reset(wheelload_mhe_state *mhe) {
    mhe->K = 0;
    (void)memset(mhe->S, 0, sizeof mhe->S);
    (void)memset(mhe->ARR, 0, sizeof mhe->ARR);
    (void)memset(mhe->XW, 0, sizeof mhe->XW);
    (void)memset(mhe->YW, 0, sizeof mhe->YW);
    (void)memset(mhe->BETA, 0, sizeof mhe->BETA);
    (void)memset(mhe->INFO, 0, sizeof mhe->INFO);
    for (int i = 0; i < NB; ++i) {
        mhe->INFO[i * NK + i] = BETA_INFO0[i];
    }
    for (int j = 0; j < N; ++j) {
        (void)memcpy(mhe->S[j].z, X0, sizeof X0);
        (void)memcpy(mhe->S[j].kfx, X0, sizeof X0);
        (void)memcpy(mhe->HIST[j], X0, sizeof X0);
    }
@@ reset_filter
}

/* Position of entry (r, c), r <= c, among the window Hessian's values (CSC order), or -1 when
   the pattern has no such entry. */
static int position(int r, int c) {
    int low = COLUMN_START[c], high = COLUMN_START[c + 1] - 1;
    while (low <= high) {
        int middle = (low + high) / 2;
        if (ROW_INDEX[middle] == r) {
            return middle;
        }
        if (ROW_INDEX[middle] < r) {
            low = middle + 1;
        } else {
            high = middle - 1;
        }
    }
    return -1;
}

/* Add v to entry (r, c) of a Hessian: ld > 0, a dense ld x ld row-major one (a sample's local
   terms); ld == 0, the window's values at the pattern (upper triangle: r > c is its mirror's). */
static void add_entry(double *H, int ld, int r, int c, double v) {
    if (ld > 0) {
        H[r * ld + c] += v;
        return;
    }
    int i = r <= c ? position(r, c) : -1;
    if (i >= 0) {
        H[i] += v;
    }
}

/* H[cols, cols] += M^T Wt M, g[cols] -= M^T Wt r (H as add_entry's); M is k x nc
   (row-major); Wt is k x k when full, else its diagonal (k entries). */
static void add_rows(double *H, int ld, double *g, const int *cols, int nc, const double *M,
                     int k, const double *r, const double *Wt, bool full) {
    double MW[32][8];
    for (int a = 0; a < nc; ++a) {
        for (int i = 0; i < k; ++i) {
            double s = 0.0;
            if (full) {
                for (int m = 0; m < k; ++m) {
                    s += M[m * nc + a] * Wt[m * k + i];
                }
            } else {
                s = M[i * nc + a] * Wt[i];
            }
            MW[a][i] = s;
        }
    }
    for (int a = 0; a < nc; ++a) {
        for (int b = 0; b < nc; ++b) {
            double s = 0.0;
            for (int i = 0; i < k; ++i) {
                s += MW[a][i] * M[i * nc + b];
            }
            add_entry(H, ld, cols[a], cols[b], s);
        }
        double s = 0.0;
        for (int i = 0; i < k; ++i) {
            s += MW[a][i] * r[i];
        }
        g[cols[a]] -= s;
    }
}

/* The data rows of a sample over [loads (W), biases (NB)]: Ms (4 x NM), and for the soft
   constraint Mc (3 x NM), each scaled by the rows' square-root weights. */
static void row_matrices(const sample_t *s, double *Ms, double *Mc) {
    (void)memset(Ms, 0, sizeof(double) * 4u * ((size_t)W + (size_t)NB)); /* 4 x NM */
    for (int i = 0; i < 4; ++i) {
#if HARD
        Ms[i * NM] = -LOAD_SCALE * NULL_VECTOR[i];
#else
        Ms[i * NM + i] = -LOAD_SCALE;
#endif
#if ND > 0
        for (int c = 0; c < ND; ++c) {
            double v = 0.0;
            for (int m = 0; m < 4; ++m) {
                v += s->Jd[i * 4 + m] * TRAVEL_BASIS[m * ND + c];
            }
            Ms[i * NM + W + c] = -v * TRAVEL_UNIT;
        }
#endif
#if HARD && NB > ND
        for (int c = 0; c < NB - ND; ++c) {
            double v = 0.0;
            for (int m = 0; m < 3; ++m) {
                v += PINV[i * 3 + m] * s->Ba[m * 2 + ACC_COLS[c]] * (s->lc[m] > 0.0);
            }
            Ms[i * NM + W + ND + c] = v;
        }
#endif
        for (int c = 0; c < NM; ++c) {
            Ms[i * NM + c] *= s->ls[i];
        }
    }
#if !HARD
    (void)memset(Mc, 0, sizeof(double) * 3u * ((size_t)W + (size_t)NB)); /* 3 x NM */
    for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < 4; ++c) {
            Mc[i * NM + c] = -A_MATRIX[i * 4 + c] * LOAD_SCALE;
        }
#if NB > ND
        for (int c = 0; c < NB - ND; ++c) {
            Mc[i * NM + W + ND + c] = -s->Ba[i * 2 + ACC_COLS[c]];
        }
#endif
        for (int c = 0; c < NM; ++c) {
            Mc[i * NM + c] *= s->lc[i];
        }
    }
#else
    (void)Mc;
#endif
}

/* One residual group with its loss into the sample's local (H, g); plus: its e+ offset. */
static void group(double *H, double *g, const double *M, int k, const double *r, int robust,
                  double kappa, double mu, int plus) {
    int cols[NM + 8];
    for (int c = 0; c < W; ++c) {
        cols[c] = c;
    }
    for (int c = 0; c < NB; ++c) {
        cols[W + c] = WIDTH + c;
    }
    double ones[4] = {1.0, 1.0, 1.0, 1.0};
    if (!robust) {
        add_rows(H, NL, g, cols, NM, M, k, r, ones, false);
        return;
    }
    double full[4 * (NM + 8)], weights[4];
    int nc = NM + 2 * k;
    for (int c = 0; c < k; ++c) {
        cols[NM + c] = plus + c;
        cols[NM + k + c] = plus + k + c;
    }
    for (int i = 0; i < k; ++i) {
        weights[i] = kappa;
        for (int c = 0; c < nc; ++c) {
            full[i * nc + c] = 0.0;
        }
        for (int c = 0; c < NM; ++c) {
            full[i * nc + c] = M[i * NM + c];
        }
        full[i * nc + NM + i] = -1.0;
        full[i * nc + NM + k + i] = 1.0;
    }
    add_rows(H, NL, g, cols, nc, full, k, r, weights, false);
    for (int c = 0; c < 2 * k; ++c) {
        g[plus + c] += mu;
    }
}

/* The sample's data rows as (Hl, gl) over its block and the biases (physical units). */
static void local_terms(sample_t *s) {
    double Ms[4 * NM], Mc[3 * NM], r[4];
    (void)memset(s->Hl, 0, sizeof s->Hl);
    (void)memset(s->gl, 0, sizeof s->gl);
    row_matrices(s, Ms, Mc);
    for (int i = 0; i < 4; ++i) {
        r[i] = -s->ls[i] * (s->z[i] - s->xp[i]);
    }
    group(s->Hl, s->gl, Ms, 4, r, SUSPENSION_ROBUST, KAPPA_S, MU_S, W);
#if !HARD
    for (int i = 0; i < 3; ++i) {
        r[i] = -s->lc[i] * s->b[i];
    }
    group(s->Hl, s->gl, Mc, 3, r, CONSTRAINT_ROBUST, KAPPA_C, MU_C, W + 2 * NS);
#endif
}

/* The window's Hessian values at the pattern and linear term (physical costs; scaled by COST
   on loading). */
static void assemble(wheelload_mhe_state *mhe, int j0, const double *prior,
                     const double *arrival) {
    (void)memset(mhe->HV, 0, sizeof mhe->HV);
    (void)memset(mhe->GD, 0, sizeof mhe->GD);
    double X[4 * W];
    (void)memset(X, 0, sizeof X);
    for (int i = 0; i < 4; ++i) {
#if HARD
        X[i] = LOAD_SCALE * NULL_VECTOR[i];
#else
        X[i * 4 + i] = LOAD_SCALE;
#endif
    }
    for (int j = 0; j < N; ++j) {
        int base = j * WIDTH;
        if (j < j0) {
            for (int a = 0; a < W; ++a) {
                add_entry(mhe->HV, 0, base + a, base + a, 1.0 / COST);
            }
            continue;
        }
        int map[NL];
        for (int a = 0; a < NL; ++a) {
            map[a] = a < WIDTH ? base + a : N * WIDTH + a - WIDTH;
        }
        for (int a = 0; a < NL; ++a) {
            for (int b = 0; b < NL; ++b) {
                add_entry(mhe->HV, 0, map[a], map[b], mhe->S[j].Hl[a * NL + b]);
            }
            mhe->GD[map[a]] += mhe->S[j].gl[a];
        }
        int cols[2 * W];
        double r[4];
        for (int a = 0; a < W; ++a) {
            cols[a] = base + a;
            cols[W + a] = base - WIDTH + a;
        }
        if (j == j0) {
            double weight[16];
            for (int e = 0; e < 16; ++e) {
                weight[e] = arrival[e] / (COST * LOAD_SCALE * LOAD_SCALE);
            }
            for (int i = 0; i < 4; ++i) {
                r[i] = prior[i] - mhe->S[j].xp[i];
            }
            add_rows(mhe->HV, 0, mhe->GD, cols, W, X, 4, r, weight, true);
        } else if (mhe->S[j].link > 0.0) {
            double M[4 * 2 * W], link[4];
            for (int i = 0; i < 4; ++i) {
                for (int a = 0; a < W; ++a) {
                    M[i * 2 * W + a] = X[i * W + a];
                    M[i * 2 * W + W + a] = -X[i * W + a];
                }
                r[i] = -(mhe->S[j].xp[i] - mhe->S[j - 1].xp[i]);
                link[i] = mhe->S[j].link;
            }
            add_rows(mhe->HV, 0, mhe->GD, cols, 2 * W, M, 4, r, link, false);
        } else {
            /* no link to the previous sample (link 0: the log's first) */
        }
    }
#if NB > 0
    int cols[NB];
    double eye[NB * NB];
    (void)memset(eye, 0, sizeof eye);
    for (int a = 0; a < NB; ++a) {
        cols[a] = N * WIDTH + a;
        eye[a * NB + a] = 1.0;
    }
    add_rows(mhe->HV, 0, mhe->GD, cols, NB, eye, NB, mhe->BETA, mhe->INFO, true);
#endif
}

#if NB > 0
/* Effective (IRLS) weight of a row at residual rho [sigma]. */
static double effective(int robust, double corner, double scale, double rho) {
    if (!robust) {
        return 1.0;
    }
    return scale * fmin(1.0, corner / fmax(fabs(rho), 1e-12));
}

/* The bias information of the window's oldest sample with its loads eliminated, at the
   solution v (Schur complement; rows at the loss's effective weight), added to INFO. */
static void leaving_information(wheelload_mhe_state *mhe, const OSQPFloat *v) {
    const sample_t *s = &mhe->S[0];
    double beta[NB], x[4], delta[4] = {0.0, 0.0, 0.0, 0.0}, ba[2] = {0.0, 0.0};
    for (int a = 0; a < NB; ++a) {
        beta[a] = (double)v[N * WIDTH + a];
    }
    for (int i = 0; i < 4; ++i) {
#if HARD
        x[i] = s->xp[i] + LOAD_SCALE * NULL_VECTOR[i] * (double)v[0];
#else
        x[i] = s->xp[i] + LOAD_SCALE * (double)v[i];
#endif
#if ND > 0
        for (int c = 0; c < ND; ++c) {
            delta[i] += TRAVEL_BASIS[i * ND + c] * beta[c] * TRAVEL_UNIT;
        }
#endif
    }
#if NB > ND
    for (int c = 0; c < NB - ND; ++c) {
        ba[ACC_COLS[c]] = beta[ND + c]; /* ax, ay */
    }
#endif
    double Ms[4 * NM], Mc[3 * NM], weights[7], M[7 * NM];
    row_matrices(s, Ms, Mc);
    int k = 4;
    for (int i = 0; i < 4; ++i) {
        double jd = 0.0;
        for (int m = 0; m < 4; ++m) {
            jd += s->Jd[i * 4 + m] * delta[m];
        }
        double rho = s->ls[i] * (s->z[i] - jd - x[i]);
        weights[i] = effective(SUSPENSION_ROBUST, CORNER_S, SCALE_S, rho);
    }
    (void)memcpy(M, Ms, sizeof Ms);
#if !HARD
    for (int i = 0; i < 3; ++i) {
        double r = s->b[i] - s->Ba[i * 2] * ba[0] - s->Ba[i * 2 + 1] * ba[1];
        for (int c = 0; c < 4; ++c) {
            r -= A_MATRIX[i * 4 + c] * x[c];
        }
        weights[4 + i] = effective(CONSTRAINT_ROBUST, CORNER_C, SCALE_C, s->lc[i] * r);
    }
    (void)memcpy(M + 4 * NM, Mc, sizeof Mc);
    k = 7;
#else
    (void)ba;
#endif
    double F[NM * NM];
    for (int a = 0; a < NM; ++a) {
        for (int b = 0; b < NM; ++b) {
            double t = 0.0;
            for (int i = 0; i < k; ++i) {
                t += M[i * NM + a] * weights[i] * M[i * NM + b];
            }
            F[a * NM + b] = t;
        }
    }
    double Fyy[W * W], inverse[W * W];
    for (int a = 0; a < W; ++a) {
        for (int b = 0; b < W; ++b) {
            Fyy[a * W + b] = F[a * NM + b] + (a == b ? 1e-12 : 0.0);
        }
    }
    invert(Fyy, W, inverse);
    for (int a = 0; a < NB; ++a) {
        for (int b = 0; b < NB; ++b) {
            double t = F[(W + a) * NM + W + b];
            for (int c = 0; c < W; ++c) {
                for (int e = 0; e < W; ++e) {
                    t -= F[c * NM + W + a] * inverse[c * W + e] * F[e * NM + W + b];
                }
            }
            mhe->INFO[a * NK + b] += t;
        }
    }
}
#endif

/* Loads [N] from one sample's QP variables (clipped_loads). */
static bool checked(const OSQPFloat *block, const sample_t *s, double *loads) {
    return clipped_loads(block, s->lower, s->upper, s->xp, loads);
}

/* The window's minimiser when no sample has a data term: the prior carried unchanged. */
static void prior_solution(wheelload_mhe_state *mhe, int j0, const double *prior) {
    double solution[N][W];
    for (int j = 0; j < N; ++j) {
        for (int a = 0; a < W; ++a) {
            solution[j][a] = (double)mhe->XW[j * WIDTH + a];
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
        num += Wn[r] * (prior[r] - mhe->S[j0].xp[r]);
    }
    double omega = num / nWn / LOAD_SCALE;
    for (int j = j0; j < N; ++j) {
        if (j > j0) {
            double step = 0.0;
            for (int r = 0; r < 4; ++r) {
                step += NULL_VECTOR[r] * (mhe->S[j].xp[r] - mhe->S[j - 1].xp[r]);
            }
            omega -= step / LOAD_SCALE;
        }
        solution[j][0] = omega;
    }
#else
    for (int j = j0; j < N; ++j) {
        for (int a = 0; a < 4; ++a) {
            solution[j][a] = prior[a] / LOAD_SCALE;
        }
    }
#endif
    for (int j = 0; j < N; ++j) {
        for (int a = 0; a < WIDTH; ++a) {
            double v = a < W ? solution[j][a] : 0.0;
            if (a < W && j >= j0) {
                v = fmin(fmax(v, mhe->S[j].lower[a]), mhe->S[j].upper[a]);
            }
            mhe->XW[j * WIDTH + a] = (OSQPFloat)v;
        }
    }
}

int wheelload_mhe_step(wheelload_mhe_state *mhe, const double *u, double dt,
                      wheelload_mhe_output *out) {
    double u0[N_INPUTS], valid[N_INPUTS], cost = COST;
    (void)memset(out, 0, sizeof *out);
    double previous_P[16];
@@ interval_and_inputs
    double kf_std[4];
    kf_step(mhe, u, dt, mhe->FALLBACK, kf_std);
    sample_t *s = &mhe->S[0];
    (void)memmove(mhe->S, mhe->S + 1, sizeof(sample_t) * ((size_t)N - 1u));
    s = &mhe->S[N - 1];
    {
        double h[W * W], g[W], link, lo[W], hi[W], used[N_USED];
        wheelload_mhe_terms(u0, valid, &dt, mhe->FALLBACK, P_VECTOR, TUNING, &cost, h, g, &link,
                            s->xp, lo, hi, s->b, used);
        for (int i = 0; i < N_USED; ++i) {
            out->flags |= used[i] < 0.5 ? UPDATE_FLAGS[i] : 0u;
        }
        s->link = mhe->K == 0 ? 0.0 : link / (COST * LOAD_SCALE * LOAD_SCALE);
        (void)memcpy(s->lower, lo, sizeof lo);
        (void)memcpy(s->upper, hi, sizeof hi);
    }
    {
        double Jd[16], Ba[6];
        wheelload_mhe_residual_rows(u0, valid, &dt, P_VECTOR, TUNING, s->z, Jd, Ba, s->ls, s->lc);
        for (int r = 0; r < 4; ++r) {
            for (int c = 0; c < 4; ++c) {
                s->Jd[r * 4 + c] = Jd[c * 4 + r]; /* column-major */
            }
        }
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 2; ++c) {
                s->Ba[r * 2 + c] = Ba[c * 3 + r];
            }
        }
    }
    (void)memcpy(s->kfx, mhe->FALLBACK, sizeof mhe->FALLBACK);
    local_terms(s);
    (void)memmove(mhe->ARR[0], mhe->ARR[1], sizeof(double) * 16u * ((size_t)N - 1u));
    arrival_weight(mhe->K == 0, previous_P, dt, mhe->ARR[N - 1]);
    int j0 = mhe->K < N - 1 ? (int)(N - 1 - mhe->K) : 0;
    if (mhe->K == 0) {
        (void)osqp_update_rho(&mhe->osqp.solver, (OSQPFloat)RHO0);
    }
    (void)memmove(mhe->XW, mhe->XW + WIDTH, sizeof(OSQPFloat) * ((size_t)N - 1u) * (size_t)WIDTH);
    (void)memmove(mhe->YW, mhe->YW + WIDTH, sizeof(OSQPFloat) * ((size_t)N - 1u) * (size_t)WIDTH);
    bool data = false;
    for (int j = j0; j < N; ++j) {
        for (int i = 0; i < 4; ++i) {
            data = data || mhe->S[j].ls[i] != 0.0;
        }
        for (int i = 0; i < 3; ++i) {
            data = data || mhe->S[j].lc[i] != 0.0;
        }
    }
    int status = 1;
    out->iterations = 0;
    if (!data) {
        prior_solution(mhe, j0, mhe->HIST[N - 1]);
    } else {
        assemble(mhe, j0, mhe->HIST[0], mhe->ARR[j0]);
        for (int i = 0; i < NNZ; ++i) {
            mhe->PX[i] = (OSQPFloat)(COST * mhe->HV[i]);
        }
        for (int i = 0; i < NQ; ++i) {
            double low = 0.0, high = 0.0;
            if (i < N * WIDTH) {
                int j = i / WIDTH, a = i % WIDTH;
                if (j >= j0) {
                    low = a < W ? mhe->S[j].lower[a] : 0.0;
                    high = a < W ? mhe->S[j].upper[a] : (double)OSQP_INFTY;
                }
            } else {
                low = -BETA_BOUND[i - N * WIDTH];
                high = BETA_BOUND[i - N * WIDTH];
            }
            mhe->Q[i] = (OSQPFloat)(COST * mhe->GD[i]);
            mhe->L[i] = (OSQPFloat)fmax(low, -(double)OSQP_INFTY);
            mhe->U[i] = (OSQPFloat)fmin(high, (double)OSQP_INFTY);
        }
        if (finite_data(mhe->PX, NNZ, mhe->Q, mhe->L, mhe->U, NQ, true)) {
            (void)osqp_update_data_mat(&mhe->osqp.solver, mhe->PX, NULL, NNZ, NULL,
                                 NULL, 0);
            (void)osqp_update_data_vec(&mhe->osqp.solver, mhe->Q, mhe->L, mhe->U);
            (void)osqp_warm_start(&mhe->osqp.solver, mhe->XW, mhe->YW);
@@ solve
        if (status == 1) {
            (void)memcpy(mhe->XW, mhe->osqp.solver.solution->x, sizeof mhe->XW);
            (void)memcpy(mhe->YW, mhe->osqp.solver.solution->y, sizeof mhe->YW);
        }
    }
    double x[4];
    bool failed = status != 1 || !checked(mhe->XW + (N - 1) * WIDTH, s, x);
    if (failed) {
        fallback_loads(mhe->FALLBACK, mhe->HIST[N - 1], x);
    }
#if NB > 0
    else {
        for (int a = 0; a < NB; ++a) {
            mhe->BETA[a] =
                fmin(fmax((double)mhe->XW[N * WIDTH + a], -BETA_BOUND[a]), BETA_BOUND[a]);
        }
        if (mhe->K >= N - 1) {
            leaving_information(mhe, mhe->XW);
        }
    }
    {
        double walk = s->link > 0.0 ? 1.0 / (Q_DENSITY * s->link) : 0.0;
        double a[NB * NB], covariance[NB * NB];
        (void)memcpy(a, mhe->INFO, sizeof a);
        invert(a, NB, covariance);
        for (int i = 0; i < NB; ++i) {
            covariance[i * NB + i] += BETA_DENSITY[i] * walk;
        }
        invert(covariance, NB, a);
        for (int r = 0; r < NB; ++r) {
            for (int c = 0; c < NB; ++c) {
                mhe->INFO[r * NK + c] = 0.5 * (a[r * NB + c] + a[c * NB + r]);
            }
        }
    }
#endif
    (void)memmove(mhe->HIST[0], mhe->HIST[1], sizeof(double) * 4u * ((size_t)N - 1u));
    (void)memcpy(mhe->HIST[N - 1], x, sizeof x);
    ++mhe->K;
    /* the output: the window's estimate of sample k - LAG (window sample OUTPUT_SAMPLE) */
    const sample_t *lagged = &mhe->S[OUTPUT_SAMPLE];
#if LAG == 0
    (void)memcpy(out->loads, x, sizeof x);
#else
    if (failed) {
        (void)memcpy(out->loads, x, sizeof x);
    } else if (!checked(mhe->XW + OUTPUT_SAMPLE * WIDTH, lagged, out->loads)) {
        fallback_loads(lagged->kfx, mhe->HIST[N - 1], out->loads);
    } else {
        /* the window's estimate of sample k - LAG, within its bounds */
    }
#endif
    for (int r = 0; r < 3; ++r) {
        out->residual[r] = lagged->b[r];
        for (int c = 0; c < 4; ++c) {
            out->residual[r] -= A_MATRIX[r * 4 + c] * out->loads[c];
        }
    }
    (void)memcpy(out->std, kf_std, sizeof kf_std);
#if NB > 0
    int nr = 0;
#if ND > 0
    for (int i = 0; i < 4; ++i) {
        double v = 0.0;
        for (int c = 0; c < ND; ++c) {
            v += TRAVEL_BASIS[i * ND + c] * mhe->BETA[c];
        }
        out->bias[nr++] = v * TRAVEL_UNIT;
    }
#endif
    for (int c = ND; c < NB; ++c) {
        out->bias[nr++] = mhe->BETA[c];
    }
#endif
    out->fallback = failed;
    return status;
}
