/*
 * An instance's own unit (instance.h): its states by name, its messages, its call sequence
 * refused with the states it is allowed in, its values checked, its model data built from
 * the parameters, and the model evaluated where the instance stands. The semantics are
 * runtime/adapter.py's (the pythonfmu flavour); the component itself is the generated model.c.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "instance.h"
#include "text.h"

THREAD_LOCAL Instance *updating_instance;

/* The states by name in messages, in the order runtime/adapter.py lists them (sorted). */
static const int MODE_ORDER[] = {CONTINUOUS_TIME_MODE, EVENT_MODE, INITIALIZATION_MODE,
                                 INSTANTIATED, STEP_COMPLETE, STEP_FAILED, TERMINATED};

const char *mode_name(const Instance *instance, int mode) {
    for (int bit = 0; bit < MODES; bit++)
        if (mode == 1 << bit) return instance->face->mode_names[bit];
    return "unknown";
}

void log_status(const Instance *instance, Status status, const char *format, ...) {
    va_list args;
    va_start(args, format);
    host_log_formatted(&instance->log, status, format, args);
    va_end(args);
}

int call_refused(Instance *instance, int claimed, int allowed, const char *function) {
    if (!claimed) {
        host_log_overlap(&instance->log, &instance->call, function);
        return 0;
    }
    char list[256] = "";
    for (size_t i = 0; i < sizeof MODE_ORDER / sizeof MODE_ORDER[0]; i++) {
        if (!(allowed & MODE_ORDER[i])) continue;
        if (list[0]) strncat(list, ", ", sizeof list - strlen(list) - 1);
        strncat(list, mode_name(instance, MODE_ORDER[i]), sizeof list - strlen(list) - 1);
    }
    log_status(instance, STATUS_ERROR, "%s is not allowed in state %s (allowed in: %s); call "
               "ignored", function, mode_name(instance, instance->s.mode), list);
    call_end(instance, STATUS_ERROR);
    return 0;
}

/* --- values and model data ------------------------------------------------------------ */

int variable_problem(unsigned vr, double value, char *message, size_t size) {
    const VariableInfo *variable = &MODEL_INFO.variables[vr];
    char text[REPR_SIZE];
    if (!isfinite(value)) {
        snprintf(message, size, "%s = %s %s is not a finite number", variable->name,
                 format_repr(value, text), variable->unit);
        return 1;
    }
    if ((variable->constraint == POSITIVE && value <= 0.0) ||
        (variable->constraint == NON_NEGATIVE && value < 0.0)) {
        snprintf(message, size, "%s = %s %s must be %s", variable->name,
                 format_repr(value, text), variable->unit,
                 variable->constraint == POSITIVE ? "positive" : "zero or positive");
        return 1;
    }
    return 0;
}

static void table_points(const TableInfo *table, const double *values, double *xs, double *ys) {
    for (size_t i = 0; i < table->size; i++) {
        xs[i] = values[table->abscissae[i]];
        ys[i] = values[table->ordinates[i]];
    }
}

/* As ComponentDefinition.check_parameters: each parameter, then each table. */
int parameter_problem(const double *values, char *message, size_t size) {
    char problem[MESSAGE_SIZE];
    for (unsigned vr = FIRST_PARAMETER; vr < FIRST_STATE; vr++) {
        if (variable_problem(vr, values[vr], problem, sizeof problem)) {
            snprintf(message, size, "parameter %s", problem);
            return 1;
        }
        /* As definition.magnitude_problem: outside these, 1/k or k*k overflows. */
        double size_of = fabs(values[vr]);
        if (values[vr] != 0.0 && !(size_of >= SMALLEST_PARAMETER && size_of <= LARGEST_PARAMETER)) {
            char text[REPR_SIZE];
            snprintf(message, size, "parameter %s = %s %s is outside the magnitudes the model's "
                     "arithmetic takes (" PARAMETER_MAGNITUDES ")",
                     MODEL_INFO.variables[vr].name, format_repr(values[vr], text),
                     MODEL_INFO.variables[vr].unit);
            return 1;
        }
    }
    for (int t = 0; t < MODEL_TABLES; t++) {
        const TableInfo *table = &MODEL_INFO.tables[t];
        double xs[HERMITE_POINTS], ys[HERMITE_POINTS];
        table_points(table, values, xs, ys);
        if (hermite_problem(xs, ys, table->size, problem, sizeof problem)) {
            snprintf(message, size, "%s table: %s", table->name, problem);
            return 1;
        }
        for (size_t i = 0; table->dissipative && i < table->size; i++) {
            if (xs[i] * ys[i] < 0.0 || (xs[i] == 0.0 && ys[i] != 0.0)) {
                snprintf(message, size, "%s table: %s %.6g %s at %s %.6g %s would feed energy "
                         "in; a %s's %s takes the sign of its %s", table->name, table->ordinate,
                         ys[i], table->ordinate_unit, table->abscissa, xs[i],
                         table->abscissa_unit, table->name, table->ordinate, table->abscissa);
                return 1;
            }
        }
    }
    return 0;
}

void build_model_data(ModelData *data, const double *values) {
    model_derive(data, values);
    for (int t = 0; t < MODEL_TABLES; t++) {
        const TableInfo *table = &MODEL_INFO.tables[t];
        double xs[HERMITE_POINTS], ys[HERMITE_POINTS];
        table_points(table, values, xs, ys);
        hermite_build(&data->tables[t], xs, ys, table->size);
    }
}

void reset_instance(Instance *instance) {
    Snapshot *s = &instance->s;
    memset(s, 0, sizeof *s);
    s->mode = INSTANTIATED;
    for (int vr = 0; vr < MODEL_VARIABLES; vr++) {
        double start = MODEL_INFO.variables[vr].start;
        s->values[vr] = isnan(start) ? 0.0 : start;
    }
    s->tolerance = DEFAULT_RTOL;
    instance->outputs_fresh = 0;
    instance->returned_early = 0;
}

int model_now(Instance *instance, Now *now) {
    Snapshot *s = &instance->s;
    if (s->initialized) {
        now->data = &instance->data;
        now->state = s->state;
        now->x = s->deflection;
        now->v = s->rate;
        now->contact = s->contact;
        return 1;
    }
    char problem[MESSAGE_SIZE];
    if (parameter_problem(s->values, problem, sizeof problem)) return 0;
    now->x = s->values[INPUT_DEFLECTION];
    now->v = s->values[INPUT_RATE];
    now->contact = model_contact(now->x, now->v);
    build_model_data(&now->scratch, s->values);
    model_initial_state(&now->scratch, now->x, now->v, now->relaxed);
    now->data = &now->scratch;
    now->state = now->relaxed;
    return 1;
}

void log_outside_region(const Instance *instance, const char *function, const double *X) {
    char states[MESSAGE_SIZE / 2] = "", text[REPR_SIZE];
    for (int i = 0; i < MODEL_CONTINUOUS; i++) {
        size_t used = strlen(states);
        snprintf(states + used, sizeof states - used, "%s%s = %s", i ? ", " : "",
                 MODEL_INFO.variables[FIRST_STATE + i].name, format_repr(X[i], text));
    }
    log_status(instance, STATUS_DISCARD, "%s: at t = %.9g s the states (%s) are outside the "
               "region the model is defined in; retry with a smaller step", function,
               instance->s.time, states);
}

int non_finite(Instance *instance, const char *function, unsigned first, const double *values,
               int n, double x, double v) {
    int i = first_non_finite(values, n);
    if (i < 0) return 0;
    const VariableInfo *input = MODEL_INFO.variables;
    char a[REPR_SIZE], b[REPR_SIZE], c[REPR_SIZE];
    log_status(instance, STATUS_DISCARD, "%s: %s would be %s at %s = %s %s, %s = %s %s: "
               "beyond what the model can give; retry with a smaller step or smaller inputs",
               function, MODEL_INFO.variables[first + i].name, format_repr(values[i], a),
               input[INPUT_DEFLECTION].name, format_repr(x, b), input[INPUT_DEFLECTION].unit,
               input[INPUT_RATE].name, format_repr(v, c), input[INPUT_RATE].unit);
    return 1;
}
