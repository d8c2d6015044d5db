/* Instruction-count driver for a generated C controller step (see
 * bench/step/step_count.sh): 1000 steps of the Zhang & Zeng controller
 * at states near the paper's x(0), as tests/flight_example/examples/step_count.rs
 * does for the generated Rust. The state and command have the controller's
 * real type (double, or float for a `precision f32` build). */
#include <stdio.h>

#include "zhang_multiobjective.h"

/* Keeps the compiler from hoisting the step out of the loop. */
static volatile double sink;

int main(void) {
    zhang_multiobjective_t s;
    ZHANG_MULTIOBJECTIVE_REAL x[6] = {0.08, -0.05, 0.1, 0.12, 0.06, -0.08};
    ZHANG_MULTIOBJECTIVE_REAL u[3];
    double acc = 0.0;
    int k;
    zhang_multiobjective_init(&s);
    for (k = 0; k < 1000; k++) {
        x[0] = 0.08 + 1e-5 * (double)(k % 7);
        zhang_multiobjective_step(&s, x, u);
        acc += u[0];
    }
    sink = acc;
    printf("%.17g\n", acc);
    return 0;
}
