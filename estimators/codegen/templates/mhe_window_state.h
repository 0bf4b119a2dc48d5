/* The state of one instance with robust losses or bias states (mhe_window.c). */

/* One sample of the window: its rows and the fallback's estimate. */
typedef struct {
    double z[4], Jd[16], b[3], Ba[6], ls[4], lc[3], xp[4], link;
    double lower[WHEELLOAD_MHE_W], upper[WHEELLOAD_MHE_W];
    /* the sample's data rows over its block and the biases */
    double Hl[WHEELLOAD_MHE_NL * WHEELLOAD_MHE_NL], gl[WHEELLOAD_MHE_NL];
    double kfx[4]; /* the fallback's estimate of the sample */
} wheelload_mhe_sample;

typedef struct wheelload_mhe_state {
    wheelload_mhe_sample S[WHEELLOAD_MHE_N]; /* the window, oldest first */
    double ARR[WHEELLOAD_MHE_N][16];  /* arrival weight c s^2 Pi^-1 of a window starting there */
    double HIST[WHEELLOAD_MHE_N][4];  /* estimates of the samples before; the prior is row 0 */
    /* the window's Hessian values at the pattern (CSC order) and linear term (scratch) */
    double HV[WHEELLOAD_MHE_NNZ], GD[WHEELLOAD_MHE_NQ];
    /* OSQP's vectors: warm start, q, l, u and the Hessian values in CSC order */
    OSQPFloat XW[WHEELLOAD_MHE_NQ], YW[WHEELLOAD_MHE_NQ], Q[WHEELLOAD_MHE_NQ];
    OSQPFloat L[WHEELLOAD_MHE_NQ], U[WHEELLOAD_MHE_NQ], PX[WHEELLOAD_MHE_NNZ];
    double BETA[WHEELLOAD_MHE_NK], INFO[WHEELLOAD_MHE_NK * WHEELLOAD_MHE_NK]; /* biases, info */
    double FALLBACK[4]; /* the fallback filter's (or held) estimate */
    long K;             /* samples since the reset */
@KF_MEMBER@
    wheelload_mhe_workspace osqp;            /* this instance's solver */
    const struct wheelload_mhe_state *self; /* where the reset left it (see wheelload_mhe.h) */
} wheelload_mhe_state;
