/*
 * The integrator's loop around the generated step: runtime/integrator.py's
 * Rosenbrock.integrate and its single-step path, statement for statement. The step itself,
 * its factorisation of W and its error norm are generated from the ROS34PW2 tableau
 * (model_factor, model_step in model.c); the constants come from integrator.py through
 * model_config.h.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "integrator.h"

#define N MODEL_INTEGRATED

/* As integrator.invert: Gauss-Jordan with partial pivoting (the first largest pivot). */
int invert(int n, double *matrix, double *inverse) {
    double work[SLOTS(MODEL_INTEGRATED)][2 * SLOTS(MODEL_INTEGRATED)];
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 2 * n; j++)
            work[i][j] = j < n ? matrix[i * n + j] : (i == j - n ? 1.0 : 0.0);
    for (int col = 0; col < n; col++) {
        int pivot = col;
        for (int i = col + 1; i < n; i++)
            if (fabs(work[i][col]) > fabs(work[pivot][col])) pivot = i;
        if (work[pivot][col] == 0.0 || !isfinite(work[pivot][col])) return 0;
        for (int j = 0; j < 2 * n; j++) {
            double swap = work[col][j];
            work[col][j] = work[pivot][j];
            work[pivot][j] = swap;
        }
        double scale = 1.0 / work[col][col];
        for (int j = 0; j < 2 * n; j++) work[col][j] = work[col][j] * scale;
        for (int i = 0; i < n; i++) {
            if (i != col && work[i][col] != 0.0) {
                double factor = work[i][col];
                for (int j = 0; j < 2 * n; j++) work[i][j] = work[i][j] - factor * work[col][j];
            }
        }
    }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) inverse[i * n + j] = work[i][n + j];
    return 1;
}

/* A communication step that is one integrator step, fused with the closed-form part: 1
   when taken, 0 (nothing changed) when integrate would do anything else. */
int single_step(ModelData *m, Memory *memory, double *state, double x, double u, double h) {
    if (MODEL_INFO.unilateral && !(x > 0.0 && x + u * h > 0.0)) return 0;
    double h_control;
    if (!memory->has_h_next) h_control = h;
    else if (memory->h_next < h) return 0; /* the controller wants more than one step */
    else h_control = memory->h_next;
    double y[SLOTS(N)], y_new[SLOTS(N)], w[W_SIZE], error;
    int uses;
    model_start(m, state, x, y);
    double same = SAME_STEP_SIZE * h;
    double gap = memory->w_h - h;
    if (memory->w_uses > 0 && -same <= gap && gap <= same && memory->w_uses < MAX_W_REUSE) {
        memcpy(w, memory->w, sizeof w);
        uses = memory->w_uses + 1;
    } else {
        if (!model_factor(m, y, u, h, w)) return 0;
        uses = 1;
    }
    if (!model_step(m, y, u, h, memory->rtol, w, y_new, &error)) return 0;
    if (!(error <= 1.0)) return 0;
    double allowed = error > 0.0 ? h * SAFETY * pow(error, SQUARED_ERROR_EXPONENT) : INFINITY;
    double grown = STEP_GROWTH_LIMIT * h_control;
    double shrunk = STEP_SHRINK_LIMIT * h_control;
    memory->has_h_next = 1;
    memory->h_next = allowed > grown ? grown : allowed > shrunk ? allowed : shrunk;
    memory->w_h = h;
    memcpy(memory->w, w, sizeof w);
    memory->w_uses = uses;
    memory->accepted_steps++;
    model_exact(m, state, x, u, h);
    for (int i = 0; i < N; i++) state[i] = y_new[i];
    return 1;
}

/* Advance y over `duration` with u held: 0, or 1 with a message and y untouched. */
int integrate(ModelData *m, Memory *memory, double *y, double u, double duration,
              char *message, size_t size) {
    if (duration <= 0.0 || N == 0) return 0;
    double rtol = memory->rtol;
    double current[SLOTS(N)], trial[SLOTS(N)], w[W_SIZE], error;
    memcpy(current, y, sizeof current);
    /* h is the step size the controller wants; the step tried may be cut short to land on
       the end of the interval, and the controller then scales its own h. */
    double h = memory->has_h_next ? memory->h_next : duration;
    double h_min = 1e-12 * duration;
    double end = duration * (1.0 - 1e-13);
    double t = 0.0;
    long steps = 0;
    int just_rejected = 0;
    for (;;) {
        double remaining = duration - t;
        double h_try = h < remaining ? h : remaining;
        if (++steps > MAX_STEPS_PER_CALL) {
            snprintf(message, size, "integrator needed more than %d steps for a %.6g s "
                     "interval at tolerance %.3g", MAX_STEPS_PER_CALL, duration, rtol);
            return 1;
        }
        int have_w;
        if (memory->w_uses > 0 && fabs(memory->w_h - h_try) <= SAME_STEP_SIZE * h_try &&
            memory->w_uses < MAX_W_REUSE) {
            memory->w_h = h_try;
            memory->w_uses++;
            have_w = 1;
        } else {
            have_w = model_factor(m, current, u, h_try, w);
            if (have_w) {
                memcpy(memory->w, w, sizeof w);
                memory->w_h = h_try;
                memory->w_uses = 1;
            } else {
                memory->w_uses = 0;
            }
        }
        if (!have_w || !model_step(m, current, u, h_try, rtol, memory->w, trial, &error)) {
            memory->rejected_steps++;
            memory->w_uses = 0;
            h = h_try * REGION_SHRINK;
            just_rejected = 1;
        } else {
            double allowed = error > 0.0 ? h_try * SAFETY * pow(error, SQUARED_ERROR_EXPONENT)
                                         : INFINITY;
            if (error <= 1.0) {
                memory->accepted_steps++;
                memcpy(current, trial, sizeof current);
                t += h_try;
                double grown = STEP_GROWTH_LIMIT * h;
                double shrunk = STEP_SHRINK_LIMIT * h;
                h = allowed > grown ? grown : (allowed > shrunk ? allowed : shrunk);
                if (just_rejected) {
                    h = h_try < h ? h_try : h;
                    just_rejected = 0;
                }
                memory->has_h_next = 1;
                memory->h_next = h;
                if (t >= end) {
                    memcpy(y, current, sizeof current);
                    return 0;
                }
                continue;
            }
            memory->rejected_steps++;
            memory->w_uses = 0;
            double shrunk = STEP_SHRINK_LIMIT * h_try;
            h = allowed > shrunk ? allowed : shrunk;
            if (just_rejected) {
                /* A second failure in a row: the estimate is not yet in its asymptotic
                   regime (a stiff boundary layer): cut hard. */
                h = shrunk < h ? shrunk : h;
            }
            just_rejected = 1;
        }
        if (h < h_min) {
            int n = snprintf(message, size, "integrator step size fell below %.3g s without "
                             "meeting tolerance %.3g (state ", h_min, rtol);
            for (int i = 0; i < N && n > 0 && (size_t)n < size; i++)
                n += snprintf(message + n, size - (size_t)n, "%s%.6g", i ? ", " : "", y[i]);
            if (n > 0 && (size_t)n < size) snprintf(message + n, size - (size_t)n, ")");
            return 1;
        }
    }
}
