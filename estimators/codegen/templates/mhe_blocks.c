/* Blocks both window drivers (mhe_plain.c, mhe_window.c) of wheelload_mhe.c share: the code
 * generator splices each in where a driver has the line "@@ NAME"; a block runs from its
 * "@@ NAME" line here to the next. This comment is not emitted.
 *   reset_filter: the end of wheelload_mhe_reset: the fallback, the instance's own solver set
 *                 up afresh (OSQP's generated values) and its rho reset;
 *   interval_and_inputs: a rejected interval holds the last estimate, else the inputs' masks;
 *   solve: the end of the driver's "QP data finite" branch (loaded and warm-started): solve,
 *          or the sample is not handed to OSQP. */
@@ reset_filter
    (void)memcpy(mhe->FALLBACK, X0, sizeof X0);
    kf_reset(mhe);
    wheelload_mhe_workspace_init(&mhe->osqp);
    (void)osqp_update_rho(&mhe->osqp.solver, (OSQPFloat)RHO0);
    mhe->self = mhe;
@@ interval_and_inputs
    if (mhe->self != mhe) { /* never reset, or copied or moved since: its solver is elsewhere */
        out->flags = 255u;
        return WHEELLOAD_MHE_NOT_RESET;
    }
    kf_covariance(mhe, previous_P);
    if (!(dt > 0.0 && dt < MAX_INTERVAL) || dt * INTERVAL_BAND < DT) {
        (void)memcpy(out->loads, mhe->HIST[N - 1], sizeof out->loads);
        kf_held(mhe, u, dt, mhe->HIST[N - 1], out->std, out->residual);
        out->flags = dt * INTERVAL_BAND < DT && dt > 0.0 ? 255u | INTERVAL_SHORT : 255u;
        return 0;
    }
    for (int i = 0; i < N_INPUTS; ++i) {
        valid[i] = isfinite(u[i]) ? 1.0 : 0.0;
        u0[i] = valid[i] != 0.0 ? u[i] : 0.0;
    }
@@ solve
            (void)osqp_solve(&mhe->osqp.solver);
            status = (int)mhe->osqp.solver.info->status_val;
            out->iterations = (int)mhe->osqp.solver.info->iter;
        } else {
            status = OSQP_UNSOLVED; /* not handed to OSQP: the filter's estimate */
        }
