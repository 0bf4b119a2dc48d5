/* wheelload_mhe_main.c: run the embedded MHE over text files of input rows, one instance per
   file, interleaved sample by sample (instance i takes its sample k, then instance i + 1).

       wheelload_mhe INPUTS.txt ESTIMATES.csv [INPUTS2.txt ESTIMATES2.csv ...]

   Each row: the interval dt [s] before the sample, then the WHEELLOAD_MHE_N_INPUTS inputs in
   wheelload.models.INPUTS order ('nan' = missing); a log that ends leaves the others running.
   Output CSV per log: fz_fl..fz_rr (of sample k - lag), std_fl..std_rr, residual_0..2, status,
   iterations, fallback, flags, osqp_float_bytes, bias_0..; exit 2 on bad use. */
#include <stdio.h>
#include <stdlib.h>
#include "osqp.h"
#include "wheelload_mhe.h"

#define ROW_SIZE (1 + WHEELLOAD_MHE_N_INPUTS)

typedef struct {
    FILE *in, *out;
    int running;
    wheelload_mhe_state state; /* this log's estimator */
} instance_t;

/* One sample of an instance: read a row, step, write the estimate; 0 at the end of its log. */
static int advance(instance_t *instance) {
    double row[ROW_SIZE];
    int i;
    for (i = 0; i < ROW_SIZE; ++i)
        if (fscanf(instance->in, "%lf", &row[i]) != 1) return 0;
    wheelload_mhe_output o;
    int status = wheelload_mhe_step(&instance->state, row + 1, row[0], &o);
    FILE *out = instance->out;
    for (i = 0; i < 4; ++i) fprintf(out, "%.9g,", o.loads[i]);
    for (i = 0; i < 4; ++i) fprintf(out, "%.9g,", o.std[i]);
    for (i = 0; i < 3; ++i) fprintf(out, "%.9g,", o.residual[i]);
    fprintf(out, "%d,%d,%d,%u,%d", status, o.iterations, o.fallback, o.flags,
            (int)sizeof(OSQPFloat));
    for (i = 0; i < WHEELLOAD_MHE_N_BIAS; ++i) fprintf(out, ",%.9g", o.bias[i]);
    fprintf(out, "\n");
    return 1;
}

int main(int argc, char **argv) {
    if (argc < 3 || argc % 2 != 1) {
        fprintf(stderr, "usage: %s INPUTS.txt ESTIMATES.csv [INPUTS2.txt ESTIMATES2.csv ...]\n",
                argv[0]);
        return 2;
    }
    int n = (argc - 1) / 2, status = 0;
    instance_t *instances = calloc((size_t)n, sizeof *instances);
    if (!instances) {
        fprintf(stderr, "%s: cannot allocate %d states\n", argv[0], n);
        return 2;
    }
    for (int k = 0; k < n && status == 0; ++k) {
        instance_t *instance = &instances[k];
        instance->in = fopen(argv[1 + 2 * k], "r");
        if (!instance->in) {
            fprintf(stderr, "%s: cannot open\n", argv[1 + 2 * k]);
            status = 2;
            break;
        }
        instance->out = fopen(argv[2 + 2 * k], "w");
        if (!instance->out) {
            fprintf(stderr, "%s: cannot write\n", argv[2 + 2 * k]);
            status = 2;
            break;
        }
        fprintf(instance->out,
                "fz_fl,fz_fr,fz_rl,fz_rr,std_fl,std_fr,std_rl,std_rr,residual_0,residual_1,"
                "residual_2,status,iterations,fallback,flags,osqp_float_bytes");
        for (int i = 0; i < WHEELLOAD_MHE_N_BIAS; ++i) fprintf(instance->out, ",bias_%d", i);
        fprintf(instance->out, "\n");
        wheelload_mhe_reset(&instance->state);
        instance->running = 1;
    }
    for (int running = status == 0; running;) {
        running = 0;
        for (int k = 0; k < n; ++k) {
            if (instances[k].running) instances[k].running = advance(&instances[k]);
            running |= instances[k].running;
        }
    }
    for (int k = 0; k < n; ++k) {
        if (instances[k].in) fclose(instances[k].in);
        if (instances[k].out && fclose(instances[k].out) != 0 && status == 0) {
            fprintf(stderr, "%s: write error\n", argv[2 + 2 * k]);
            status = 1;
        }
    }
    free(instances);
    return status;
}
