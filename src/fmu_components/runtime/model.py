"""What a component is to both runtimes: its equations as expression trees (``Equations``),
and those equations compiled to Python with the parameter values of one instance
(``Model``, the pythonfmu flavour's model).

A component's physics (rubber.py, damper.py) builds one ``Equations``: the names below are
what its statements read and write. The native flavour prints the same statements as C
(``fmu_components.export.cgen``); the hand-written runtimes of both flavours (this module and
``cosim``/``integrator`` here, ``c/`` there) drive them the same way.

Names the statements use:

* parameters by their FMU variable names, and the derived ``constants``, computed once
  when the instance is initialised (statements over the parameters);
* ``x`` the deflection at the start of a step or segment, ``u`` the rate the rubber or rotor
  sees over it, ``h`` its length, ``v`` the input rate (outputs, messages);
* ``state[i]`` the model's state list, of which the first ``integrated`` entries are
  integrated and the others advanced in closed form (``exact``);
* the integrated system: stage state ``Y0 ..``, derivatives ``f0 ..``, Jacobian entries
  ``j{row}_{column}``, start state ``y0 ..``.
"""

import math

from .expressions import (FUNCTIONS, Assign, Element, PythonPrinter, Require, Symbol, all_of,
                          any_of, equal, where, wrap)
from .hermite import check_monotone_table, shared_curve
from .integrator import compile_python, jacobian_statements


class Table:
    """A monotone Hermite curve through parameter points: abscissa and ordinate names, what
    each means (name, unit), and whether it is a dissipative characteristic (the ordinate
    takes the abscissa's sign, as a dashpot's torque takes its rate's)."""

    def __init__(self, name, abscissae, ordinates, abscissa=("x", ""), ordinate=("y", ""),
                 dissipative=False):
        self.name = name
        self.abscissae = tuple(abscissae)
        self.ordinates = tuple(ordinates)
        self.abscissa, self.ordinate = abscissa, ordinate
        self.dissipative = dissipative

    def points(self, values):
        return [values[n] for n in self.abscissae], [values[n] for n in self.ordinates]

    def check(self, values):
        """A message if these parameter values cannot define the curve, else None."""
        xs, ys = self.points(values)
        problem = check_monotone_table(xs, ys)
        if problem:
            return f"{self.name} table: {problem}"
        for x, y in zip(xs, ys) if self.dissipative else ():
            if x * y < 0.0 or (x == 0.0 and y != 0.0):
                return (f"{self.name} table: {self.ordinate[0]} {y:.6g} {self.ordinate[1]} at "
                        f"{self.abscissa[0]} {x:.6g} {self.abscissa[1]} would feed energy in; "
                        f"a {self.name}'s {self.ordinate[0]} takes the sign of its "
                        f"{self.abscissa[0]}")
        return None


class InputLimit:
    """The deflections a model cannot take: after ``lines``, ``test`` must hold for the
    deflection ``x`` at the current ``state``, else ``message`` says why. A deflection it
    takes runs ``accept`` (after ``lines``, whose values it may use), which may rewrite
    the state for it."""

    def __init__(self, lines, test, message, accept=()):
        self.lines, self.test, self.message = lines, test, message
        self.accept = list(accept)


class ContinuousTime:
    """The equations as a host's integrator sees them (Model Exchange, and the states and
    derivatives any host may read): the first ``states`` entries of the state list are the
    continuous states, driven by the input rate itself rather than a held one.

    * ``rates``: statements setting ``f{i}`` for the continuous states beyond the integrated
      ones (reading ``Y{i}``, ``u`` and the ``held`` values);
    * ``nominals``: each state's typical magnitude (over the parameters);
    * ``output_lines`` and ``outputs``: the outputs from ``state``, ``x``, ``v`` where they
      differ from the co-simulation's (None: the same);
    * ``event_indicators``: expressions over ``x`` whose sign changes are events (a contact:
      the rubber rate is ``contact * v``, ``contact`` being 1 or 0 as the events set it).
    """

    def __init__(self, states, nominals, rates=(), output_lines=None, outputs=None,
                 event_indicators=()):
        self.states = states
        self.nominals = [wrap(e) for e in nominals]
        self.rates = list(rates)
        self.output_lines = output_lines
        self.outputs = None if outputs is None else [wrap(e) for e in outputs]
        self.event_indicators = [wrap(e) for e in event_indicators]


class Equations:
    """A component's equations (see the module docstring for the names).

    * ``integrated``, ``state_size``: the integrated entries of the state list, and all;
    * ``constants``: statements deriving constants from the parameters;
    * ``held``: statements depending on ``u`` alone, once per step; ``stage``: the
      derivatives ``f0 ..`` at ``Y0 ..``; ``jacobian``: the entries ``j{i}_{k}`` of d f / d Y
      (after ``stage``, whose values they may use; entries left unset are zero);
    * ``region``: a condition on ``Y0 ..`` that fails where the model is not defined, or
      None;
    * ``start``: statements setting ``y0 ..`` from ``state`` and ``x`` (None: the first
      entries of ``state``); ``exact``: statements advancing the other entries of ``state``
      over a step in closed form (after ``held``);
    * ``initial_state``: the state list, relaxed at the initial inputs ``x``, ``v``;
    * ``output_lines`` then ``outputs``: the outputs from ``state``, ``x``, ``v``;
    * ``input_limit``: an ``InputLimit``, or None; ``failure_hint``: a Message over
      ``state`` and ``v`` added to the message of a step that fails, or None;
    * ``state_scale``: the typical magnitude of each integrated state (over the parameters);
    * ``tables``: the ``Table`` curves ``Lookup`` nodes name;
    * ``unilateral``: a contact whose rubber is deformed only while ``x > 0``: a step that
      crosses ``x = 0`` is two segments, the rate ``u`` being 0 on the part out of contact;
    * ``continuous``: the ``ContinuousTime`` view.
    """

    def __init__(self, *, integrated, state_size, stage, jacobian, initial_state, outputs,
                 state_scale, constants=(), held=(), region=None, start=None, exact=(),
                 output_lines=(), input_limit=None, failure_hint=None, tables=(),
                 unilateral=False, continuous=None):
        self.integrated = integrated
        self.state_size = state_size
        self.constants = list(constants)
        self.held = list(held)
        self.stage = list(stage)
        self.jacobian = list(jacobian)
        self.region = region
        self.start = None if start is None else list(start)
        self.exact = list(exact)
        self.initial_state = [wrap(e) for e in initial_state]
        self.output_lines = list(output_lines)
        self.outputs = [wrap(e) for e in outputs]
        self.input_limit = input_limit
        self.failure_hint = failure_hint
        self.state_scale = [wrap(e) for e in state_scale]
        self.tables = list(tables)
        self.unilateral = unilateral
        self.continuous = continuous

    def start_statements(self):
        if self.start is not None:
            return self.start
        return [Assign(Symbol(f"y{i}"), Element("state", i)) for i in range(self.integrated)]

    def constant_names(self):
        return [statement.target.name for statement in self.constants]

    def contact_mode(self):
        """The contact's mode at deflection x and rate v, as both runtimes take it where no
        event has set it: 1 in contact, or touching and pressing on, else 0; always 1 for a
        two-sided component."""
        if not self.unilateral:
            return wrap(1.0)
        x, v = Symbol("x"), Symbol("v")
        return where(any_of(x > 0.0, all_of(equal(x, 0.0), v > 0.0)), 1.0, 0.0)

    # --- the continuous-time view: what Model Exchange and directional derivatives print ---

    def rate_statements(self):
        """f0 .. of every continuous state at Y0 .., inputs x, v and the contact mode; they
        fail outside the model's region."""
        u = Symbol("contact") * Symbol("v") if self.unilateral else Symbol("v")
        region = [] if self.region is None else [Require(self.region)]
        return ([Assign(Symbol("u"), u)] + self.held + region + self.stage
                + self.continuous.rates)

    def continuous_output_statements(self):
        """(statements, outputs) from the continuous states `state[i]`, x and v; they fail
        outside the model's region."""
        view = self.continuous
        lines = [Assign(Symbol(f"Y{i}"), Element("state", i)) for i in range(self.integrated)]
        lines += [] if self.region is None else [Require(self.region)]
        if view.outputs is None:
            return lines + self.output_lines, self.outputs
        return lines + view.output_lines, view.outputs


def rate_segments(x, v, h, unilateral):
    """Pieces of a step, (duration, rate the rubber sees, deflection at the start), over
    which that rate is constant: the whole step, or for a contact the parts in and out of
    contact (it is deformed only while x > 0)."""
    if not unilateral:
        return ((h, v, x),)
    x_end = x + v * h
    if x > 0.0 and x_end > 0.0:
        return ((h, v, x),)
    if x <= 0.0 and x_end <= 0.0:
        return ((h, 0.0, x),)
    crossing = -x / v  # time at which x reaches 0, inside the step
    if x > 0.0:
        return ((crossing, v, x), (h - crossing, 0.0, x + v * crossing))
    return ((crossing, 0.0, x), (h - crossing, v, x + v * crossing))


class Model:
    """One instance's equations compiled to Python, parameter values written in as
    literals. ``values``: parameter name -> value (every parameter the equations name)."""

    def __init__(self, equations, values=None):
        values = dict(values or {})
        self.equations = equations
        self.compiled_steps = {}  # tableau name -> the integrator's step for this model
        self.integrated_size = equations.integrated
        self.state_size = equations.state_size
        self.tables = {table.name: shared_curve(*table.points(values))
                       for table in equations.tables}
        self.namespace = {name: getattr(math, name) for name in FUNCTIONS}
        for name, curve in self.tables.items():
            self.namespace[f"{name}_value"] = curve.value
            self.namespace[f"{name}_slope"] = curve.slope
        self.literals = values
        derived = self._function("derive()", equations.constants,
                                 "(" + "".join(f"{n}, " for n in equations.constant_names()) + ")")
        self.literals = {**values, **dict(zip(equations.constant_names(), derived()))}
        self.state_scale = [float(s) for s in self._values((), equations.state_scale)]
        view = equations.continuous
        self.nominals = self.rates = None
        if view is not None:  # the continuous-time view: nominals and rates of the states
            self.nominals = [float(s) for s in self._values((), view.nominals)]
            Ys = [f"Y{i}" for i in range(view.states)]
            self.rates = self._function(
                "rates(X, x, v, contact)", equations.rate_statements(),
                self._tuple([f"f{i}" for i in range(view.states)]),
                [f"({''.join(name + ', ' for name in Ys)}) = X"], extra=Ys)
        self.contact = self._function("contact(x, v)", [],
                                      self._print(equations.contact_mode(), (), ("x", "v")))
        n = equations.integrated
        Y = [f"Y{i}" for i in range(n)]
        unpack = [f"({''.join(name + ', ' for name in Y)}) = y"] if n else []
        self.rhs = self._function("rhs(y, u)", equations.held + equations.stage,
                                  self._tuple([f"f{i}" for i in range(n)]), unpack)
        self.jacobian = self._function(
            "jacobian(y, u)", jacobian_statements(equations),
            self._tuple([self._tuple([f"j{i}_{k}" for k in range(n)]) for i in range(n)]), unpack)
        self._start = self._function("start(state, x)", equations.start_statements(),
                                     self._tuple([f"y{i}" for i in range(n)]))
        self._exact = self._function("exact(state, u, h, x)", equations.held + equations.exact,
                                     "None")
        initial = ", ".join(self._print(e, (), ("x", "v")) for e in equations.initial_state)
        self._initial_state = self._function("initial_state(x, v)", [], f"[{initial}]")
        self.outputs = self._function("outputs(state, x, v)", equations.output_lines,
                                      self._tuple([self._print(e, equations.output_lines, ("state", "x", "v"))
                                                   for e in equations.outputs]))
        limit = equations.input_limit
        self._input_problem = self._take_input = None
        if limit is not None:
            self._input_problem = self._function(
                "input_problem(state, x)", limit.lines + [Assign(Symbol("ok"), limit.test)],
                f"None if ok else {self._message(limit.message, limit.lines)}")
            if limit.accept:
                self._take_input = self._function("take_input(state, x)",
                                                  limit.lines + limit.accept, "None")
        hint = equations.failure_hint
        self._failure_hint = None if hint is None else self._function(
            "failure_hint(state, v)", [], self._message(hint, (), ("state", "v")))

    # --- compiling ------------------------------------------------------------------------

    def printer(self, known=()):
        return PythonPrinter(self.literals, known)

    def _print(self, expression, lines=(), known=()):
        printer = self.printer(known)
        printer.statements(lines, "pass")  # learn the names the lines assign
        return printer.expression(expression)

    def _message(self, message, lines=(), known=("state", "x")):
        printer = self.printer(known)
        printer.statements(lines, "pass")
        return printer.message(message)

    def _function(self, signature, statements, result, prologue=(), extra=None):
        """A generated function: the prologue, the statements printed, then `result`;
        `extra`: the names the prologue sets (default: the integrated states Y0 ..)."""
        arguments = signature[signature.index("(") + 1:-1]
        names = [a.strip() for a in arguments.split(",") if a.strip()]
        if prologue:
            names += extra if extra is not None else [f"Y{i}" for i in range(self.equations.integrated)]
        body = list(prologue) + self.printer(names).statements(statements, "return None")
        text = "\n".join([f"def {signature}:", *[f"    {line}" for line in body],
                          f"    return {result}"]) + "\n"
        name = signature[:signature.index("(")]
        return compile_python(text, self.namespace, f"<{name}>")[name]

    def _values(self, lines, expressions):
        return self._function("values()", lines, self._tuple([self._print(e, lines)
                                                               for e in expressions]))()

    @staticmethod
    def _tuple(items):
        return "(" + "".join(f"{item}, " for item in items) + ")"

    # --- the model, for the co-simulation -------------------------------------------------

    def initial_state(self, x, v):
        """Relaxed at the initial inputs (spec sections 2 and 3)."""
        return self._initial_state(x, v)

    def check_input(self, state, x):
        """A message if the model cannot take deflection x in this state, else None."""
        return None if self._input_problem is None else self._input_problem(state, x)

    def take_input(self, state, x):
        """Rewrite the state for a new deflection x, which check_input has accepted."""
        if self._take_input is not None:
            self._take_input(state, x)

    def advance(self, state, x, v, h, integrator):
        """Advance the state over a step of length h with rate v held. Returns None, or an
        error message with the state untouched: it is written only once all of the step
        has succeeded."""
        n = self.integrated_size
        work = state[:]
        for duration, rate, x_start in rate_segments(x, v, h, self.equations.unilateral):
            if duration > 0.0:
                if n:
                    y = list(self._start(work, x_start))
                    problem = integrator.integrate(self, y, rate, duration)
                    if problem:
                        if self._failure_hint is not None:
                            problem = f"{problem}; {self._failure_hint(state, v)}"
                        return problem
                self._exact(work, rate, duration, x_start)
                if n:
                    work[:n] = y
        state[:] = work
        return None
