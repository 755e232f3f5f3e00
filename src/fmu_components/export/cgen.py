"""The native flavour's model code: a component's equations printed as C.

The same expression trees the pythonfmu flavour prints as Python at run time
(``runtime/rubber.py``, ``runtime/damper.py``) and the integrator's step statements from the
same tableau (``runtime/integrator.py``) are printed here by ``CPrinter`` into two files per
component, written at build time and never committed:

* ``model_config.h``: the component's sizes, for the runtime's arrays, and the constants
  the runtime shares with the Python flavour (the parameter bounds and their message, the
  integrator's and the rate check's);
* ``model.c``: ``MODEL_INFO`` (variables, constraints, ranges, tables: the component's
  definition as C data) and the ``model_*`` functions that ``c/model.h`` declares (the
  contact's mode among them).

Everything else (the FMI calls, the co-simulation step, the integrator's loop, the Hermite
curve, states and logging) is the hand-written runtime in ``c/``, the same for every
component.
"""

import math
import re

from ..runtime.expressions import FUNCTIONS, Format, GenerationError, Printer, Symbol, Tangent
from ..runtime import cosim, integrator
from ..runtime.definition import LARGEST_PARAMETER, PARAMETER_MAGNITUDES, SMALLEST_PARAMETER
from ..runtime.integrator import ROS34PW2, factor_statements, step_statements
from .model_description import EVENT_INDICATOR, fmi3_references

C_KEYWORDS = set("""auto break case char const continue default do double else enum extern float
for goto if inline int long register restrict return short signed sizeof static struct switch
typedef union unsigned void volatile while""".split())

CAUSALITY = {"input": "CAUSALITY_INPUT", "output": "CAUSALITY_OUTPUT",
             "parameter": "CAUSALITY_PARAMETER", "local": "CAUSALITY_LOCAL"}
CONSTRAINT = {None: "ANY_FINITE", "positive": "POSITIVE", "zero or positive": "NON_NEGATIVE"}


def identifier(name):
    """A C identifier for a variable name ('elastic.a0' -> 'elastic_a0')."""
    text = re.sub(r"\W+", "_", name).strip("_")
    if not text or text[0].isdigit() or text in C_KEYWORDS or text in FUNCTIONS:
        raise GenerationError(f"variable name {name!r} has no safe C identifier")
    return text


def c_string(text):
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def c_number(value):
    if math.isinf(value):
        return "-INFINITY" if value < 0 else "INFINITY"
    if math.isnan(value):
        return "NAN"
    return repr(float(value))


class CPrinter(Printer):
    """C99. Parameters and derived constants are read from the model data (``m->K``);
    locals are declared where they are first assigned."""

    ABSOLUTE = "fabs"

    def __init__(self, constants, tables, known=()):
        super().__init__(known, constants)
        self.indices = constants  # name -> index in m->K
        self.tables = tables  # name -> index in m->tables
        self.used = {}  # constant name -> C identifier, for the function's prologue
        self.declared = set(known)

    def symbol(self, name):
        if name in self.indices:
            self.used[name] = identifier(name)
            return self.used[name]
        return name

    def prologue(self):
        return [f"const double {c} = m->K[{self.indices[name]}]; /* {name} */"
                for name, c in sorted(self.used.items(), key=lambda item: self.indices[item[0]])]

    def _print_Logical(self, node):
        if node.op == "and":
            return (f"{self._operand(node.left, self.AND)} && "
                    f"{self._operand(node.right, self.AND + 1)}", self.AND)
        # either side of || in parentheses unless it binds tighter than && (-Wparentheses)
        return (f"{self._operand(node.left, self.NOT)} || "
                f"{self._operand(node.right, self.NOT)}", self.OR)

    def _print_Not(self, node):
        return f"!{self._operand(node.operand, self.ATOM)}", self.UNARY

    def _print_Compare(self, node):
        text, _ = super()._print_Compare(node)
        return text, self.COMPARE

    def _print_Lookup(self, node):
        function = "hermite_slope" if node.slope else "hermite_value"
        return (f"{function}(&m->tables[{self.tables[node.table]}], "
                f"{self.expression(node.argument)})", self.ATOM)

    @staticmethod
    def conditional(test, then, otherwise):
        return f"({test} ? {then} : {otherwise})"

    @staticmethod
    def requirement(test, fail):
        return [f"if (!({test})) {fail}"]

    def assignment(self, target, value):
        if isinstance(target, Symbol) and target.name not in self.declared | self.constants:
            self.declared.add(target.name)
            self.known.add(target.name)
            return f"double {target.name} = {value};"
        return super().assignment(target, value) + ";"

    def message(self, message, buffer="message", size="size"):
        """An snprintf of a Message into buffer[size]."""
        text, arguments = [], []
        for part in message.parts:
            if isinstance(part, Format):
                text.append(f"%{part.spec}")
                arguments.append(self.expression(part.value))
            else:
                text.append(part.replace("%", "%%"))
        return f"snprintf({buffer}, {size}, {', '.join([c_string(''.join(text))] + arguments)});"


class ModelCode:
    """model_config.h and model.c of one component (a catalog.ComponentDefinition)."""

    def __init__(self, definition, guid, tableau=ROS34PW2):
        self.definition = definition
        self.equations = definition.equations
        self.guid = guid
        self.tableau = tableau
        variables = definition.variables
        self.vr = {v.name: i for i, v in enumerate(variables)}
        derived = self.equations.constant_names()
        n = self.equations.integrated
        self.scale_names = [f"state_scale{i}" for i in range(n)]
        # m->K: every variable's value by value reference (the parameters are what the
        # equations read), then the derived constants and state scales
        self.constants = {v.name: self.vr[v.name] for v in definition.parameters}
        for i, name in enumerate(derived + self.scale_names):
            self.constants[name] = len(variables) + i
        self.tables = {table.name: i for i, table in enumerate(self.equations.tables)}

    def printer(self, known=(), derive=False):
        """A printer for one function; `derive`: the one that computes the derived constants,
        which may assign them."""
        constants = {n: i for n, i in self.constants.items() if not derive or n in self.vr}
        return CPrinter(constants, self.tables, known)

    def function(self, signature, statements, known, prologue=(), epilogue=(), fail="return 0;",
                 printer=None):
        """A C function: the constants the body reads, `prologue`, the statements printed,
        then `epilogue` (lines, or a function of the printer that returns lines)."""
        printer = printer or self.printer(known)
        body = printer.statements(statements, fail)
        if callable(epilogue):
            epilogue = epilogue(printer)
        lines = ["(void)m;", *prologue, *body, *epilogue]
        return "\n".join([f"{signature} {{"] + [f"    {line}" for line in printer.prologue() + lines]
                         + ["}"])

    # --- the files ----------------------------------------------------------------------

    def config_header(self):
        d, e = self.definition, self.equations
        table_points = max([len(t.abscissae) for t in e.tables], default=0)
        extra = fmi3_references(d)
        return "\n".join([
            f"/* {d.name}: sizes of the generated model (fmu_components.export.cgen). Generated at build",
            "   time; do not edit. */",
            "#ifndef MODEL_CONFIG_H",
            "#define MODEL_CONFIG_H",
            f"#define MODEL_VARIABLES {len(d.variables)}",
            f"#define MODEL_OUTPUTS {len(d.outputs)}",
            f"#define MODEL_STATES {e.state_size}",
            f"#define MODEL_INTEGRATED {e.integrated}",
            f"#define MODEL_CONSTANTS {len(d.variables) + len(e.constants) + e.integrated}",
            f"#define MODEL_TABLES {len(e.tables)}",
            f"#define MODEL_TABLE_POINTS {table_points}",
            f"#define MODEL_PARAMETERS {len(d.parameters)}",
            f"#define SMALLEST_PARAMETER {c_number(SMALLEST_PARAMETER)}",
            f"#define LARGEST_PARAMETER {c_number(LARGEST_PARAMETER)}",
            f"#define PARAMETER_MAGNITUDES {c_string(PARAMETER_MAGNITUDES)}",
            f"#define MODEL_CONTINUOUS {e.continuous.states}",
            f"#define MODEL_EVENT_INDICATORS {len(e.continuous.event_indicators)}",
            "/* What FMI 3.0 declares beyond FMI 2.0 (export/model_description.py). */",
            f"#define MODEL_EVENT_INDICATOR_REFERENCE {extra.get(EVENT_INDICATOR, 0xFFFFFFFF)}u",
            f"#define MODEL_TIME_REFERENCE {extra['time']}u",
            "/* The integrator's constants (runtime/integrator.py) and the controller's power of",
            f"   the squared error norm for the {self.tableau.name} tableau. */",
            f"#define DEFAULT_RTOL {integrator.DEFAULT_RTOL!r}",
            f"#define MAX_STEPS_PER_CALL {integrator.MAX_STEPS_PER_CALL}",
            f"#define STEP_GROWTH_LIMIT {integrator.STEP_GROWTH_LIMIT!r}",
            f"#define STEP_SHRINK_LIMIT {integrator.STEP_SHRINK_LIMIT!r}",
            f"#define SAFETY {integrator.SAFETY!r}",
            f"#define REGION_SHRINK {integrator.REGION_SHRINK!r}",
            f"#define SAME_STEP_SIZE {integrator.SAME_STEP_SIZE!r}",
            f"#define MAX_W_REUSE {integrator.Rosenbrock.MAX_W_REUSE}",
            f"#define SQUARED_ERROR_EXPONENT ({self.tableau.squared_error_exponent!r})",
            "/* The rate check's margin and floors (runtime/cosim.py). */",
            f"#define RATE_MARGIN {cosim.RATE_MARGIN!r}",
            f"#define RATE_STILL {cosim.rate_floors(d.deflection_scale)[0]!r}",
            f"#define RATE_CREEP {cosim.rate_floors(d.deflection_scale)[1]!r}",
            "/* Inside these bounds every output is finite (runtime/cosim.py, FiniteGuard). */",
            f"#define FINITE_DEFLECTION_LOW {c_number(d.finite_bounds[0][0])}",
            f"#define FINITE_DEFLECTION_HIGH {c_number(d.finite_bounds[0][1])}",
            f"#define FINITE_RATE_LOW {c_number(d.finite_bounds[1][0])}",
            f"#define FINITE_RATE_HIGH {c_number(d.finite_bounds[1][1])}",
            "#endif", ""])

    def source(self):
        return "\n\n".join([self._preamble(), self._info(), self._derive(),
                            self._initial_state(), self._start(), self._factor(), self._step(),
                            self._exact(), self._outputs(), self._contact(),
                            self._input_problem(),
                            self._take_input(), self._failure_hint(), self._nominals(),
                            self._rates(), self._continuous_outputs(),
                            self._event_indicators(), self._outputs_direction()]) + "\n"

    def _preamble(self):
        return "\n".join([
            f"/* The {self.definition.name} model: its equations (fmu_components.runtime) and the",
            f"   {self.tableau.name} step, printed as C by fmu_components.export.cgen at build time. Do not",
            "   edit; the runtime that drives these functions is hand-written (c/). */",
            '#include "model.h"', "", "#include <math.h>", "#include <stdio.h>", "",
            "/* Every stage derivative is computed; the Jacobian reads only some of them, and a",
            "   directional derivative only those along its direction. */",
            "#if defined(__GNUC__)",
            '#pragma GCC diagnostic ignored "-Wunused-variable"',
            "#endif"])

    def _info(self):
        d, e = self.definition, self.equations
        variables = ",\n".join(
            f"    {{{c_string(v.name)}, {CAUSALITY[v.causality]}, {c_string(v.unit)}, "
            f"{CONSTRAINT[v.constraint]}, {c_number(v.start if v.start is not None else math.nan)}}}"
            for v in d.variables)
        ranges = []
        for variable in d.inputs:
            low, high, measured = d.measured_ranges.get(variable.name, (-math.inf, math.inf, ""))
            ranges.append(f"{{{c_number(low)}, {c_number(high)}, {c_string(measured)}}}")
        lines = [f"static const VariableInfo VARIABLES[{len(d.variables)}] = {{\n{variables}\n}};"]
        tables = []
        for i, table in enumerate(e.tables):
            for kind, names in (("abscissae", table.abscissae), ("ordinates", table.ordinates)):
                references = ", ".join(str(self.vr[n]) for n in names)
                lines.append(f"static const unsigned TABLE{i}_{kind.upper()}[{len(names)}] = "
                             f"{{{references}}};")
            tables.append(f"{{{c_string(table.name)}, {len(table.abscissae)}, TABLE{i}_ABSCISSAE, "
                          f"TABLE{i}_ORDINATES, {c_string(table.abscissa[0])}, "
                          f"{c_string(table.abscissa[1])}, {c_string(table.ordinate[0])}, "
                          f"{c_string(table.ordinate[1])}, {int(table.dissipative)}}}")
        if tables:
            lines.append(f"static const TableInfo TABLES[{len(tables)}] = {{{', '.join(tables)}}};")
        lines.append("\n".join([
            "const ModelInfo MODEL_INFO = {",
            f"    {c_string(d.name)}, {c_string(self.guid)},",
            f"    VARIABLES, {{{', '.join(ranges)}}},",
            f"    {'TABLES' if tables else 'NULL'}, {int(e.unilateral)}",
            "};"]))
        return "\n".join(lines)

    def _derive(self):
        """The parameter values into m->K, then the derived constants and state scales."""
        e = self.equations
        printer = self.printer(derive=True)
        lines = ["for (int i = 0; i < MODEL_VARIABLES; i++) m->K[i] = values[i];"]
        body = printer.statements(e.constants, "return;")
        for name in e.constant_names():
            body.append(f"m->K[{self.constants[name]}] = {name};")
        for name, scale in zip(self.scale_names, e.state_scale):
            body.append(f"m->K[{self.constants[name]}] = {printer.expression(scale)};")
        return "\n".join(["void model_derive(ModelData *m, const double *values) {"]
                         + [f"    {line}" for line in lines + printer.prologue() + body] + ["}"])

    def _initial_state(self):
        return self.function(
            "void model_initial_state(ModelData *m, double x, double v, double *state)", [],
            ["x", "v"], prologue=["(void)x, (void)v;"],
            epilogue=lambda printer: [f"state[{i}] = {printer.expression(value)};"
                                      for i, value in enumerate(self.equations.initial_state)])

    def _start(self):
        n = self.equations.integrated
        return self.function(
            "void model_start(ModelData *m, const double *state, double x, double *y)",
            self.equations.start_statements(), ["state", "x"], fail="return;",
            prologue=["(void)x;"] + _unused(n, "state", "y"),
            epilogue=[f"y[{i}] = y{i};" for i in range(n)])

    def _factor(self):
        n = self.equations.integrated
        statements, matrix = factor_statements(self.tableau, self.equations)
        Y = [f"Y{i}" for i in range(n)]

        def epilogue(printer):
            if matrix is None:
                return [f"w[{i}] = w{i};" for i in range(n * n)] + ["return 1;"]
            entries = ", ".join(printer.expression(e) for row in matrix for e in row)
            return [f"double matrix[{n * n}] = {{{entries}}};", f"return invert({n}, matrix, w);"]

        return self.function(
            "int model_factor(ModelData *m, const double *y, double u, double h, double *w)",
            statements, ["u", "h", *Y],
            prologue=[f"const double {name} = y[{i}];" for i, name in enumerate(Y)] + ["(void)u;"]
            + _unused(n, "y"), epilogue=epilogue)

    def _step(self):
        n = self.equations.integrated
        y = [f"y{i}" for i in range(n)]
        inverse = [f"w{i}{k}" for i in range(n) for k in range(n)]
        statements = step_statements(self.tableau, self.equations,
                                     [Symbol(name) for name in self.scale_names])
        prologue = ([f"const double {name} = y[{i}];" for i, name in enumerate(y)]
                    + [f"const double {name} = w[{i}];" for i, name in enumerate(inverse)]
                    + _unused(n, "y", "u", "h", "rtol", "w", "y_new"))
        epilogue = ([f"y_new[{i}] = Y{i};" for i in range(n)]
                    + ["*error_norm = error;", "return 1;"])
        return self.function(
            "int model_step(ModelData *m, const double *y, double u, double h, double rtol, "
            "const double *w, double *y_new, double *error_norm)",
            statements, ["u", "h", "rtol", *y, *inverse], prologue=prologue, epilogue=epilogue)

    def _exact(self):
        e = self.equations
        return self.function(
            "void model_exact(ModelData *m, double *state, double x, double u, double h)",
            e.held + e.exact, ["state", "x", "u", "h"], fail="return;",
            prologue=["(void)state, (void)x, (void)u, (void)h;"])

    def _outputs(self):
        e = self.equations
        return self.function(
            "void model_outputs(ModelData *m, const double *state, double x, double v, "
            "double *outputs)", e.output_lines, ["state", "x", "v"], fail="return;",
            prologue=["(void)state, (void)v;"],
            epilogue=lambda printer: [f"outputs[{i}] = {printer.expression(value)};"
                                      for i, value in enumerate(e.outputs)])

    def _contact(self):
        """The contact's mode at x and v (model.Equations.contact_mode)."""
        printer = self.printer(["x", "v"])
        mode = printer.expression(self.equations.contact_mode())
        return "\n".join(["double model_contact(double x, double v) {", "    (void)x, (void)v;",
                          f"    return {mode};", "}"])

    def _input_problem(self):
        limit = self.equations.input_limit
        lines = [] if limit is None else limit.lines

        def epilogue(printer):
            if limit is None:
                return ["(void)message, (void)size;", "return 0;"]
            return [f"if ({printer.expression(limit.test)}) return 0;",
                    printer.message(limit.message), "return 1;"]

        return self.function(
            "int model_input_problem(ModelData *m, const double *state, double x, "
            "char *message, size_t size)", lines, ["state", "x"],
            prologue=["(void)state, (void)x;"], epilogue=epilogue)

    def _take_input(self):
        limit = self.equations.input_limit
        statements = [] if limit is None or not limit.accept else limit.lines + limit.accept
        return self.function("void model_take_input(ModelData *m, double *state, double x)",
                             statements, ["state", "x"], fail="return;",
                             prologue=["(void)state, (void)x;"])

    def _failure_hint(self):
        hint = self.equations.failure_hint
        return self.function(
            "void model_failure_hint(ModelData *m, const double *state, double v, "
            "char *message, size_t size)", [], ["state", "v"],
            prologue=["(void)state, (void)v;"],
            epilogue=lambda printer: [printer.message(hint)] if hint else
            ["if (size) message[0] = '\\0';"])

    # --- the continuous-time view: Model Exchange and directional derivatives -------------

    def _nominals(self):
        view = self.equations.continuous
        return self.function(
            "void model_nominals(ModelData *m, double *nominal)", [], [],
            epilogue=lambda printer: [f"nominal[{i}] = {printer.expression(e)};"
                                      for i, e in enumerate(view.nominals)], fail="return;")

    def _rates(self):
        """The continuous states' derivatives and, along a direction (dX, dx, dv), their
        derivatives: forward differentiation of the same statements (expressions.Tangent);
        0 outside the model's region."""
        n = self.equations.continuous.states
        Y = [f"Y{i}" for i in range(n)]
        tangent = Tangent({**{y: Symbol(f"dY{i}") for i, y in enumerate(Y)},
                           "x": Symbol("dx"), "v": Symbol("dv")})
        statements = tangent.statements(self.equations.rate_statements())
        derivatives = [tangent.derivatives.get(f"f{i}") for i in range(n)]

        def epilogue(printer):
            lines = [f"f[{i}] = f{i};" for i in range(n)]
            lines += [f"if (df) df[{i}] = {printer.expression(d) if d is not None else '0.0'};"
                      for i, d in enumerate(derivatives)]
            return lines + ["return 1;"]

        return self.function(
            "int model_rates(ModelData *m, const double *X, double x, double v, double contact, "
            "const double *dX, double dx, double dv, double *f, double *df)",
            statements, ["x", "v", "contact", "dx", "dv", *Y, *[f"dY{i}" for i in range(n)]],
            prologue=[*[f"const double {y} = X[{i}];" for i, y in enumerate(Y)],
                      *[f"const double dY{i} = dX ? dX[{i}] : 0.0;" for i in range(n)],
                      "(void)x, (void)v, (void)contact, (void)dx, (void)dv;"],
            epilogue=epilogue)

    def _direction_function(self, signature, lines, outputs, seeds, known, prologue):
        tangent = Tangent(seeds)
        statements = tangent.statements(lines)
        derivatives = [tangent.of(e) for e in outputs]

        def epilogue(printer):
            body = [f"outputs[{i}] = {printer.expression(e)};" for i, e in enumerate(outputs)]
            body += [f"if (doutputs) doutputs[{i}] = "
                     f"{printer.expression(d) if d is not None else '0.0'};"
                     for i, d in enumerate(derivatives)]
            return body + ["return 1;"]

        return self.function(signature, statements, known, prologue=prologue,
                             epilogue=epilogue)

    def _continuous_outputs(self):
        """The outputs from the continuous states X as a host's integrator sees them, and
        their derivatives along (dX, dx, dv); 0 outside the model's region."""
        n = self.equations.continuous.states
        lines, outputs = self.equations.continuous_output_statements()
        seeds = {**{("state", i): Symbol(f"dY{i}") for i in range(n)},
                 "x": Symbol("dx"), "v": Symbol("dv")}
        return self._direction_function(
            "int model_continuous_outputs(ModelData *m, const double *state, double x, double v, "
            "const double *dX, double dx, double dv, double *outputs, double *doutputs)",
            lines, outputs, seeds, ["state", "x", "v", "dx", "dv", *[f"dY{i}" for i in range(n)]],
            [*[f"const double dY{i} = dX ? dX[{i}] : 0.0;" for i in range(n)],
             "(void)state, (void)x, (void)v, (void)dx, (void)dv;"])

    def _outputs_direction(self):
        """The co-simulation's outputs and their derivatives along the inputs (dx, dv) at
        the frozen state."""
        e = self.equations
        return self._direction_function(
            "int model_outputs_direction(ModelData *m, const double *state, double x, double v, "
            "double dx, double dv, double *outputs, double *doutputs)",
            e.output_lines, e.outputs, {"x": Symbol("dx"), "v": Symbol("dv")},
            ["state", "x", "v", "dx", "dv"], ["(void)state, (void)x, (void)v, (void)dx, (void)dv;"])

    def _event_indicators(self):
        view = self.equations.continuous
        return self.function(
            "void model_event_indicators(ModelData *m, double x, double *indicators)", [], ["x"],
            prologue=["(void)x, (void)indicators;"], fail="return;",
            epilogue=lambda printer: [f"indicators[{i}] = {printer.expression(e)};"
                                      for i, e in enumerate(view.event_indicators)])


def _unused(integrated, *names):
    """A model that integrates nothing (every state in closed form) still prints the
    integrator's functions, which the runtime never calls: their arguments go unread."""
    return [f"(void){', (void)'.join(names)};"] if integrated == 0 else []
