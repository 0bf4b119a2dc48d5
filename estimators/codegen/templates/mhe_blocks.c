/* Blocks both window drivers (mhe_plain.c, mhe_window.c) of wheelload_mhe.c share: the code
 * generator splices each in where a driver has the line "@@ NAME"; a block runs from its
 * "@@ NAME" line here to the next. This comment is not emitted.
 *   reset_filter: the end of wheelload_mhe_reset, the fallback and OSQP's rho reset;
 *   interval_and_inputs: a rejected interval holds the last estimate, else the inputs' masks;
 *   solve: the end of the driver's "QP data finite" branch (loaded and warm-started): solve,
 *          or the sample is not handed to OSQP. */
@@ reset_filter
    memcpy(FALLBACK, X0, sizeof X0);
    kf_reset();
    osqp_update_rho(&wheelload_mhe_solver, (OSQPFloat)RHO0);
@@ interval_and_inputs
    kf_covariance(previous_P);
    if (!(dt > 0.0 && dt < MAX_INTERVAL)) {
        memcpy(out->loads, HIST[N - 1], sizeof out->loads);
        kf_held(u, dt, HIST[N - 1], out->std, out->residual);
        out->flags = 255u;
        return 0;
    }
    for (int i = 0; i < N_INPUTS; ++i) {
        valid[i] = isfinite(u[i]) ? 1.0 : 0.0;
        u0[i] = valid[i] != 0.0 ? u[i] : 0.0;
    }
@@ solve
            osqp_solve(&wheelload_mhe_solver);
            status = (int)wheelload_mhe_solver.info->status_val;
            out->iterations = (int)wheelload_mhe_solver.info->iter;
        } else {
            status = OSQP_UNSOLVED; /* not handed to OSQP: the filter's estimate */
        }
