/* No filter linked: the fallback is the last estimate, held (no standard deviations). */
static void kf_reset(void) {}

static void kf_covariance(double *P) {
    for (int e = 0; e < 16; ++e) P[e] = e % 5 == 0 ? P0_VAR : 0.0;
}

static void kf_step(const double *u, double dt, double *x, double *std) {
    (void)u;
    (void)dt;
    memcpy(x, HIST[N - 1], sizeof(double) * 4);
    memset(std, 0, sizeof(double) * 4);
}

static void kf_held(const double *u, double dt, const double *held, double *std,
                    double *residual) {
    (void)u;
    (void)dt;
    (void)held;
    memset(std, 0, sizeof(double) * 4);
    memset(residual, 0, sizeof(double) * 3);
}
