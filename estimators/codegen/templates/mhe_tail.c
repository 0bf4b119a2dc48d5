/* c s^2 (P + q dt I)^-1, symmetrised; the steady-state weight after the log's first sample. */
static void arrival_weight(int first, const double *P, double dt, double *weight) {
    if (first) { /* the log's first sample: the filter's diffuse prediction (m g)^2 I */
        for (int e = 0; e < 16; ++e)
            weight[e] = e % 5 == 0 ? COST * LOAD_SCALE * LOAD_SCALE / DIFFUSE_VARIANCE : 0.0;
        return;
    }
    if (!KALMAN_ARRIVAL) {
        (void)memcpy(weight, ARRIVAL_STEADY, sizeof(double) * 16);
        return;
    }
    double a[16], inverse[16];
    for (int e = 0; e < 16; ++e) a[e] = P[e] + (e % 5 == 0 ? Q_DENSITY * dt : 0.0);
    invert(a, 4, inverse);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            weight[r * 4 + c] =
                COST * LOAD_SCALE * LOAD_SCALE * (0.5 * (inverse[r * 4 + c] + inverse[c * 4 + r]));
}

size_t wheelload_mhe_state_size(void) { return sizeof(wheelload_mhe_state); }

/* A whole log in mhe, reset first (u: n x N_INPUTS, row-major; dt: the interval before each
   sample); bias: n x WHEELLOAD_MHE_N_BIAS; wall time per sample in seconds. */
void wheelload_mhe_run(wheelload_mhe_state *mhe, int n, const double *u, const double *dt,
                       double *loads, double *std, double *residual, double *bias, int *status,
                       int *iterations, int *fallback, unsigned *flags, double *seconds) {
    wheelload_mhe_reset(mhe);
    for (int k = 0; k < n; ++k) {
        struct timespec start, stop;
        wheelload_mhe_output out;
        clock_gettime(CLOCK_MONOTONIC, &start);
        status[k] = wheelload_mhe_step(mhe, u + N_INPUTS * k, dt[k], &out);
        clock_gettime(CLOCK_MONOTONIC, &stop);
        seconds[k] = (double)(stop.tv_sec - start.tv_sec)
                     + 1e-9 * (double)(stop.tv_nsec - start.tv_nsec);
        (void)memcpy(loads + 4 * k, out.loads, sizeof out.loads);
        (void)memcpy(std + 4 * k, out.std, sizeof out.std);
        (void)memcpy(residual + 3 * k, out.residual, sizeof out.residual);
        for (int i = 0; i < WHEELLOAD_MHE_N_BIAS; ++i)
            bias[WHEELLOAD_MHE_N_BIAS * k + i] = out.bias[i];
        iterations[k] = out.iterations;
        fallback[k] = out.fallback;
        flags[k] = out.flags;
    }
}
