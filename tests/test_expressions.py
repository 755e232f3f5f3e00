"""The one definition of the equations and its two printers: the expression subset is
enforced when code is generated, and Python and C print the same operations in the same
order."""

import math
import re

import pytest

from fmu_components.export.cgen import CPrinter, ModelCode
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.runtime.expressions import (Assign, Element, GenerationError, Lookup,
                                                Number, PythonPrinter, Require, Symbol, call,
                                                copysign, exp, tanh, where, wrap)


def printers(known=("x", "v"), literals=None):
    literals = literals or {"k": 1500000.0, "c": 1000.0}
    return (PythonPrinter(literals, known),
            CPrinter({name: i for i, name in enumerate(literals)}, {"dashpot": 0}, known))


def test_python_and_c_print_the_same_tree_with_the_same_grouping():
    x, v, k, c = (Symbol(n) for n in ("x", "v", "k", "c"))
    tree = x - (k * x - c) / (v + 1.5) - -x * (2.0 - v)
    python, c_printer = printers()
    python_text, c_text = python.expression(tree), c_printer.expression(tree)
    assert python_text == "x - (1500000.0 * x - 1000.0) / (v + 1.5) - -x * (2.0 - v)"
    assert c_text == "x - (k * x - c) / (v + 1.5) - -x * (2.0 - v)"
    assert eval(python_text, {"x": 0.3, "v": -0.7}) == 0.3 - (1500000.0 * 0.3 - 1000.0) / (
        -0.7 + 1.5) - -0.3 * (2.0 - -0.7)


def test_conditionals_and_absolute_values_print_alike():
    x, v = Symbol("x"), Symbol("v")
    tree = where(v > 0.0, abs(x), abs(x - v)) + copysign(1.0, v) * exp(tanh(x))
    python, c_printer = printers()
    assert python.expression(tree) == ("((x if x >= 0.0 else -x) if v > 0.0 else abs(x - v)) "
                                       "+ copysign(1.0, v) * exp(tanh(x))")
    assert c_printer.expression(tree) == ("(v > 0.0 ? (x >= 0.0 ? x : -x) : fabs(x - v)) "
                                          "+ copysign(1.0, v) * exp(tanh(x))")


def test_negating_a_negation_never_prints_a_decrement():
    x = Symbol("x")
    for printer in printers():
        assert printer.expression(-(-x)) == "-(-x)"
        assert printer.expression(Number(2.0) - Number(-3.0)) == "2.0 - -3.0"


def test_a_table_lookup_prints_as_each_runtime_names_it():
    python, c_printer = printers()
    assert python.expression(Lookup("dashpot", Symbol("v"), slope=True)) == "dashpot_slope(v)"
    assert c_printer.expression(Lookup("dashpot", Symbol("v"))) == "hermite_value(&m->tables[0], v)"


@pytest.mark.parametrize("build, message", [
    (lambda: Symbol("x") + "1", "not part of the expression subset"),
    (lambda: Symbol("x") + True, "not part of the expression subset"),
    (lambda: Number(math.inf), "not finite"),
    (lambda: call("exp", Symbol("x"), Symbol("v")), "whitelist"),
    (lambda: call("sqrt", Symbol("x")), "whitelist"),
    (lambda: bool(Symbol("x") > 0.0), "no truth value"),
])
def test_constructs_outside_the_subset_are_refused_when_built(build, message):
    with pytest.raises((GenerationError, TypeError), match=message):
        build()


def test_a_name_read_before_it_is_assigned_is_a_generation_error():
    for printer in printers(known=()):
        with pytest.raises(GenerationError, match="'y' is read before"):
            printer.statements([Assign(Symbol("z"), Symbol("y") * 2.0)], "return")


def test_a_local_may_not_take_a_parameter_name():
    for printer in printers():
        with pytest.raises(GenerationError, match="'k' is a parameter"):
            printer.statements([Assign(Symbol("k"), Symbol("x"))], "return")


def test_a_node_a_printer_does_not_know_is_an_error():
    class Power(Symbol):  # a construct no printer knows
        pass

    for printer in printers():
        with pytest.raises(GenerationError, match="cannot print Power"):
            printer.expression(Power("x") + 1.0)


def test_statements_declare_locals_once_in_c_and_guard_with_the_failure_line():
    x = Symbol("x")
    statements = [Assign(Symbol("a"), x * 2.0), Require(Symbol("a") < 1.0),
                  Assign(Symbol("a"), Symbol("a") + 1.0), Assign(Element("state", 2), Symbol("a"))]
    python, c_printer = printers()
    assert python.statements(statements, "return None") == [
        "a = x * 2.0", "if not (a < 1.0):", "    return None", "a = a + 1.0", "state[2] = a"]
    assert c_printer.statements(statements, "return 0;") == [
        "double a = x * 2.0;", "if (!(a < 1.0)) return 0;", "a = a + 1.0;", "state[2] = a;"]


@pytest.mark.parametrize("name", sorted(COMPONENTS))
def test_generated_c_uses_only_the_whitelisted_functions(name):
    source = re.sub(r'"[^"]*"', '""', ModelCode(COMPONENTS[name], "guid").source())  # no strings
    called = set(re.findall(r"\b([a-z_][a-z0-9_]*)\(", source))
    allowed = {"exp", "copysign", "tanh", "sinh", "cosh", "atanh", "fabs", "hermite_value",
               "hermite_slope", "invert", "snprintf",
               # the signatures of the generated functions themselves
               "model_derive", "model_initial_state", "model_start", "model_factor",
               "model_step", "model_exact", "model_outputs", "model_contact",
               "model_input_problem", "model_take_input", "model_failure_hint", "model_nominals",
               "model_rates", "model_continuous_outputs", "model_event_indicators",
               "model_outputs_direction", "if", "defined"}
    assert called <= allowed, called - allowed


def test_wrap_takes_numbers_and_nodes_only():
    assert isinstance(wrap(2), Number) and wrap(Symbol("x")).name == "x"
    with pytest.raises(GenerationError):
        wrap(None)
