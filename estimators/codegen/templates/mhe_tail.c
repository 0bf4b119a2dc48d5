/* c s^2 (P + q dt I)^-1, symmetrised; the steady-state weight after the log's first sample. */
static void arrival_weight(bool first, const double *P, double dt, double *weight) {
    if (first) { /* the log's first sample: the filter's diffuse prediction (m g)^2 I */
        for (int e = 0; e < 16; ++e) {
            weight[e] = e % 5 == 0 ? COST * LOAD_SCALE * LOAD_SCALE / DIFFUSE_VARIANCE : 0.0;
        }
        return;
    }
    if (!KALMAN_ARRIVAL) {
        (void)memcpy(weight, ARRIVAL_STEADY, sizeof(double) * 16u);
        return;
    }
    double a[16], inverse[16];
    for (int e = 0; e < 16; ++e) {
        a[e] = P[e] + (e % 5 == 0 ? Q_DENSITY * dt : 0.0);
    }
    invert(a, 4, inverse);
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            weight[r * 4 + c] =
                COST * LOAD_SCALE * LOAD_SCALE * (0.5 * (inverse[r * 4 + c] + inverse[c * 4 + r]));
        }
    }
}

size_t wheelload_mhe_state_size(void) { return sizeof(wheelload_mhe_state); }
