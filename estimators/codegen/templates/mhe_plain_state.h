/* The state of one instance with quadratic losses (mhe_plain.c): the window, oldest sample
 * first, in the terms of wheelload_mhe_terms (QP units). */
typedef struct wheelload_mhe_state {
    double HB[WHEELLOAD_MHE_N][WHEELLOAD_MHE_W * WHEELLOAD_MHE_W]; /* data Hessian blocks */
    double G[WHEELLOAD_MHE_N][WHEELLOAD_MHE_W];                    /* data linear terms */
    double LINK[WHEELLOAD_MHE_N], DRIFT[WHEELLOAD_MHE_N];          /* random-walk links */
    double XP[WHEELLOAD_MHE_N][4];                                 /* particular solutions */
    double LO[WHEELLOAD_MHE_N][WHEELLOAD_MHE_W], HI[WHEELLOAD_MHE_N][WHEELLOAD_MHE_W];
    double BW[WHEELLOAD_MHE_N][3];   /* each sample's equilibrium right-hand side b */
    double KFX[WHEELLOAD_MHE_N][4];  /* the fallback's estimate of each sample */
    double ARR[WHEELLOAD_MHE_N][16]; /* arrival weight c s^2 Pi^-1 of a window starting there */
    double HIST[WHEELLOAD_MHE_N][4]; /* estimates of the samples before; the prior is row 0 */
    /* OSQP's vectors: warm start, q, l, u and the Hessian values in CSC order */
    OSQPFloat XW[WHEELLOAD_MHE_NX], YW[WHEELLOAD_MHE_NY], Q[WHEELLOAD_MHE_NX];
    OSQPFloat L[WHEELLOAD_MHE_NX + 1], U[WHEELLOAD_MHE_NX + 1], PX[WHEELLOAD_MHE_NNZ];
    double VALUES[WHEELLOAD_MHE_NV]; /* Hessian: diagonal blocks, then couplings */
    double FALLBACK[4];              /* the fallback filter's (or held) estimate */
    long K;                          /* samples since the reset */
@KF_MEMBER@
    wheelload_mhe_workspace osqp;            /* this instance's solver */
    const struct wheelload_mhe_state *self; /* where the reset left it (see wheelload_mhe.h) */
} wheelload_mhe_state;
