/* No filter linked: the fallback is the last estimate, held (no standard deviations). */
static void kf_reset(wheelload_mhe_state *mhe) { (void)mhe; }

static void kf_covariance(const wheelload_mhe_state *mhe, double *P) {
    (void)mhe;
    for (int e = 0; e < 16; ++e) {
        P[e] = e % 5 == 0 ? P0_VAR : 0.0;
    }
}

static void kf_step(wheelload_mhe_state *mhe, const double *u, double dt, double *x, double *std) {
    (void)u;
    (void)dt;
    (void)memcpy(x, mhe->HIST[N - 1], sizeof(double) * 4);
    (void)memset(std, 0, sizeof(double) * 4);
}

static void kf_held(const wheelload_mhe_state *mhe, const double *u, double dt, const double *held,
                    double *std, double *residual) {
    (void)mhe;
    (void)u;
    (void)dt;
    (void)held;
    (void)memset(std, 0, sizeof(double) * 4);
    (void)memset(residual, 0, sizeof(double) * 3);
}
