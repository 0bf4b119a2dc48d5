/* The fallback filter: the library of `wheelload codegen` (wheelload_mhe_kf.c, from the same
 * vehicle file) linked in: the two-stage KF (soft constraint) or the projection KF (hard), as the
 * Python MHE's. Its estimate stands in for a sample whose QP is not solved (flagged fallback), its
 * covariance gives the Kalman arrival weight, its standard deviations are reported. Each MHE
 * instance has its own filter state (mhe->kf); the calibration is the library's default. */

static void kf_reset(wheelload_mhe_state *mhe) {
    wheelload_mhe_kf_reset(&mhe->kf, &wheelload_mhe_kf_default_params);
}

static void kf_covariance(const wheelload_mhe_state *mhe, double *P) {
    static const int index[16] = {0, 1, 2, 3, 1, 4, 5, 6, 2, 5, 7, 8, 3, 6, 8, 9};
    for (int e = 0; e < 16; ++e) {
        P[e] = (double)mhe->kf.P[index[e]];
    }
}

static void kf_run(wheelload_mhe_kf_state *state, const double *u, double dt,
                   wheelload_mhe_kf_output *output) {
    wheelload_mhe_kf_input input;
    for (int i = 0; i < N_INPUTS; ++i) {
        *wheelload_mhe_kf_input_field(&input, i) = (wheelload_mhe_kf_real)u[i];
    }
    (void)wheelload_mhe_kf_step(state, &wheelload_mhe_kf_default_params, &input,
                                (wheelload_mhe_kf_real)dt, output);
}

static void kf_step(wheelload_mhe_state *mhe, const double *u, double dt, double *x, double *std) {
    wheelload_mhe_kf_output output;
    kf_run(&mhe->kf, u, dt, &output);
    for (int i = 0; i < 4; ++i) {
        x[i] = (double)mhe->kf.x[i];
        std[i] = (double)output.std[i];
    }
}

/* A rejected interval: the filter's report of the held step, its residual moved to the held
   estimate; the filter's state is not advanced. */
static void kf_held(const wheelload_mhe_state *mhe, const double *u, double dt, const double *held,
                    double *std, double *residual) {
    wheelload_mhe_kf_state copy;
    (void)memcpy(&copy, &mhe->kf, sizeof copy);
    wheelload_mhe_kf_output output;
    kf_run(&copy, u, dt, &output);
    for (int i = 0; i < 4; ++i) {
        std[i] = (double)output.std[i];
    }
    for (int r = 0; r < 3; ++r) {
        residual[r] = (double)output.residual[r];
        for (int c = 0; c < 4; ++c) {
            residual[r] += A_MATRIX[r * 4 + c] * ((double)copy.x[c] - held[c]);
        }
    }
}
