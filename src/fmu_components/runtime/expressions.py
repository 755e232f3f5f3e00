"""Equations as expression trees, and the printer that turns them into Python.

Each component writes its equations once, as trees of the small node classes below (sympy's
habit, with none of sympy): arithmetic, comparisons, conditional expressions and a
whitelist of functions. A printer turns a tree into one language, one ``_print_<Node>``
method per node class; a language overrides only what differs. ``PythonPrinter`` (here,
because the pythonfmu flavour prints its equations at run time with the host's parameter
values baked in as literals) and ``fmu_components.export.cgen.CPrinter`` (at build time, for the
native flavour) print the same tree, so both flavours compute the same operations in the
same order: on the same libm the results agree to the bit.

A construct outside the subset cannot be built (``wrap`` refuses anything but numbers and
nodes), and a printer meets no node it does not know; a symbol read before it is assigned,
or a function outside ``FUNCTIONS``, is an error when the code is generated, never wrong
code. Statements are ``Assign`` (a local or an array element) and ``Require`` (the
generated function gives up unless a condition holds); ``Message`` is a logged text.
"""

import math

# Functions an expression may call, with their number of arguments: those of C99's libm that
# the components and the rig driver need, which Python's math module computes with that libm.
FUNCTIONS = {"exp": 1, "copysign": 2, "tanh": 1, "sinh": 1, "cosh": 1, "atanh": 1, "sin": 1}


class GenerationError(Exception):
    """The equations use something the printers cannot print."""


class Expr:
    """A node of an expression tree. Python's operators build trees."""

    __slots__ = ()

    def __add__(self, other):
        return Binary("+", self, wrap(other))

    def __radd__(self, other):
        return Binary("+", wrap(other), self)

    def __sub__(self, other):
        return Binary("-", self, wrap(other))

    def __rsub__(self, other):
        return Binary("-", wrap(other), self)

    def __mul__(self, other):
        return Binary("*", self, wrap(other))

    def __rmul__(self, other):
        return Binary("*", wrap(other), self)

    def __truediv__(self, other):
        return Binary("/", self, wrap(other))

    def __rtruediv__(self, other):
        return Binary("/", wrap(other), self)

    def __neg__(self):
        return Negate(self)

    def __abs__(self):
        return Absolute(self)

    def __lt__(self, other):
        return Compare("<", self, wrap(other))

    def __le__(self, other):
        return Compare("<=", self, wrap(other))

    def __gt__(self, other):
        return Compare(">", self, wrap(other))

    def __ge__(self, other):
        return Compare(">=", self, wrap(other))

    def __bool__(self):
        raise GenerationError("an expression has no truth value while the equations are "
                              "built: use where(), all_of() or any_of()")


def wrap(value):
    if isinstance(value, Expr):
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return Number(value)
    raise GenerationError(f"{value!r} ({type(value).__name__}) is not part of the expression "
                          f"subset")


class Number(Expr):
    __slots__ = ("value",)

    def __init__(self, value):
        value = float(value)
        if not math.isfinite(value):
            raise GenerationError(f"number {value!r} is not finite")
        self.value = value


class Symbol(Expr):
    """A named value: a parameter, a derived constant, an input, or a local."""

    __slots__ = ("name",)

    def __init__(self, name):
        self.name = name


class Element(Expr):
    """Entry `index` of an array argument (the model's state list)."""

    __slots__ = ("array", "index")

    def __init__(self, array, index):
        self.array = array
        self.index = index


class Negate(Expr):
    __slots__ = ("operand",)

    def __init__(self, operand):
        self.operand = operand


class Binary(Expr):
    __slots__ = ("op", "left", "right")

    def __init__(self, op, left, right):
        self.op, self.left, self.right = op, left, right


class Compare(Expr):
    __slots__ = ("op", "left", "right")

    def __init__(self, op, left, right):
        self.op, self.left, self.right = op, left, right


class Logical(Expr):
    __slots__ = ("op", "left", "right")  # "and" or "or"

    def __init__(self, op, left, right):
        self.op, self.left, self.right = op, left, right


class Not(Expr):
    __slots__ = ("operand",)

    def __init__(self, operand):
        self.operand = operand


class Conditional(Expr):
    """`then` if `test` holds, else `otherwise`. A shortcut is a conditional whose `then`
    is a cheaper way to the value `otherwise` gives when `test` holds: its derivative is
    `otherwise`'s."""

    __slots__ = ("test", "then", "otherwise", "shortcut")

    def __init__(self, test, then, otherwise, shortcut=False):
        self.test, self.then, self.otherwise = test, then, otherwise
        self.shortcut = shortcut


class Absolute(Expr):
    __slots__ = ("operand",)

    def __init__(self, operand):
        self.operand = operand


class Call(Expr):
    __slots__ = ("function", "arguments")

    def __init__(self, function, arguments):
        if FUNCTIONS.get(function) != len(arguments):
            raise GenerationError(f"{function}() with {len(arguments)} arguments is not in "
                                  f"the function whitelist {sorted(FUNCTIONS)}")
        self.function, self.arguments = function, tuple(wrap(a) for a in arguments)


class Lookup(Expr):
    """The monotone Hermite curve `table` (hermite.py) at `argument`: its value, or its
    slope."""

    __slots__ = ("table", "argument", "slope")

    def __init__(self, table, argument, slope=False):
        self.table, self.argument, self.slope = table, wrap(argument), slope


# --- building helpers -----------------------------------------------------------------------

def where(test, then, otherwise):
    """`then` if `test` holds, else `otherwise`; only the chosen branch is evaluated."""
    return Conditional(test, wrap(then), wrap(otherwise))


def shortcut(test, fast, general):
    """`fast` when `test` holds, which is there the value of `general`, else `general`."""
    return Conditional(test, wrap(fast), wrap(general), shortcut=True)


def equal(left, right):
    return Compare("==", wrap(left), wrap(right))


def differs(left, right):
    return Compare("!=", wrap(left), wrap(right))


def all_of(*tests):
    result = tests[0]
    for test in tests[1:]:
        result = Logical("and", result, test)
    return result


def any_of(*tests):
    result = tests[0]
    for test in tests[1:]:
        result = Logical("or", result, test)
    return result


def call(function, *arguments):
    return Call(function, arguments)


def exp(a):
    return Call("exp", (a,))


def tanh(a):
    return Call("tanh", (a,))


def sinh(a):
    return Call("sinh", (a,))


def cosh(a):
    return Call("cosh", (a,))


def atanh(a):
    return Call("atanh", (a,))


def copysign(a, b):
    return Call("copysign", (a, b))


def total(terms):
    """terms[0] + terms[1] + ..., added left to right."""
    terms = [wrap(t) for t in terms]
    result = terms[0]
    for term in terms[1:]:
        result = result + term
    return result


class Assign:
    __slots__ = ("target", "value")

    def __init__(self, target, value):
        if not isinstance(target, (Symbol, Element)):
            raise GenerationError(f"cannot assign to {target!r}")
        self.target, self.value = target, wrap(value)


class Require:
    """The generated function fails (returns its failure value) unless `test` holds."""

    __slots__ = ("test",)

    def __init__(self, test):
        self.test = test


class Format:
    __slots__ = ("value", "spec")

    def __init__(self, value, spec=".6g"):
        if spec not in (".6g", ".9g"):
            raise GenerationError(f"format {spec!r} is not one both printers write alike")
        self.value, self.spec = wrap(value), spec


class Message:
    """A log text: strings and Format(value) parts."""

    __slots__ = ("parts",)

    def __init__(self, *parts):
        self.parts = parts


# --- what depends on what --------------------------------------------------------------

def dependencies(statements, expressions, knowns):
    """For each expression, the knowns (names, or (array, index) for elements) it reads,
    through the statements before it: what a ModelStructure declares."""
    depends = {}

    def of(node):
        if isinstance(node, Symbol):
            return {node.name} if node.name in knowns else depends.get(node.name, set())
        if isinstance(node, Element):
            key = (node.array, node.index)
            return {key} if key in knowns else depends.get(key, set())
        found = set()
        for child in _children(node):
            found |= of(child)
        return found

    for statement in statements:
        if isinstance(statement, Assign):
            target = statement.target
            key = target.name if isinstance(target, Symbol) else (target.array, target.index)
            depends[key] = of(statement.value)
    return [of(wrap(e)) for e in expressions]


def _children(node):
    if isinstance(node, (Negate, Absolute, Not)):
        return (node.operand,)
    if isinstance(node, (Binary, Compare, Logical)):
        return node.left, node.right
    if isinstance(node, Conditional):
        return node.test, node.then, node.otherwise
    if isinstance(node, Call):
        return node.arguments
    if isinstance(node, Lookup):
        return (node.argument,)
    return ()


# --- derivatives -------------------------------------------------------------------------

def tangent_name(name):
    return f"d_{name}"


class Tangent:
    """Forward-mode differentiation of statements: for every value a statement computes, the
    statement for its derivative along a direction, given the derivatives of the knowns
    (``seeds``: name -> derivative expression, ``Element`` seeds by (array, index)).
    Everything else (parameters, constants) has derivative zero. Derivatives that are zero
    are not written, so the code stays as small as the dependence."""

    def __init__(self, seeds):
        self.derivatives = {}
        for known, derivative in seeds.items():
            self.derivatives[known] = wrap(derivative)

    def statements(self, statements):
        """The statements with, before each assignment, the assignment of its derivative."""
        out = []
        for statement in statements:
            if isinstance(statement, Assign):
                derivative = self.of(statement.value)
                key = (statement.target.name if isinstance(statement.target, Symbol)
                       else (statement.target.array, statement.target.index))
                name = (tangent_name(statement.target.name) if isinstance(statement.target, Symbol)
                        else f"d_{statement.target.array}{statement.target.index}")
                if derivative is None:
                    self.derivatives.pop(key, None)
                else:
                    out.append(Assign(Symbol(name), derivative))
                    self.derivatives[key] = Symbol(name)
            out.append(statement)
        return out

    def of(self, node):
        """d node, or None where it is zero."""
        method = getattr(self, f"_d_{type(node).__name__}", None)
        if method is None:
            raise GenerationError(f"no derivative of {type(node).__name__}")
        return method(node)

    def _d_Number(self, node):
        return None

    def _d_Symbol(self, node):
        return self.derivatives.get(node.name)

    def _d_Element(self, node):
        return self.derivatives.get((node.array, node.index))

    def _d_Negate(self, node):
        d = self.of(node.operand)
        return None if d is None else -d

    def _d_Binary(self, node):
        a, b = node.left, node.right
        da, db = self.of(a), self.of(b)
        if node.op in "+-":
            if db is None:
                return da
            if node.op == "-":
                db = -db
            return db if da is None else da + db
        if node.op == "*":
            terms = [t for t in (None if da is None else da * b, None if db is None else a * db)
                     if t is not None]
        else:  # d(a/b) = da/b - a db/b^2
            terms = [t for t in (None if da is None else da / b,
                                 None if db is None else -(a * db / (b * b))) if t is not None]
        return total(terms) if terms else None

    def _d_Absolute(self, node):
        d = self.of(node.operand)
        return None if d is None else where(node.operand >= 0.0, d, -d)

    def _d_Conditional(self, node):
        if node.shortcut:
            return self.of(node.otherwise)
        then, otherwise = self.of(node.then), self.of(node.otherwise)
        if then is None and otherwise is None:
            return None
        return where(node.test, 0.0 if then is None else then,
                     0.0 if otherwise is None else otherwise)

    def _d_Call(self, node):
        a = node.arguments[0]
        d = self.of(a)
        if d is None:
            return None
        if node.function == "exp":
            return node * d
        if node.function == "tanh":
            return (1.0 - node * node) * d
        if node.function == "sinh":
            return Call("cosh", (a,)) * d
        if node.function == "cosh":
            return Call("sinh", (a,)) * d
        if node.function == "atanh":
            return d / (1.0 - a * a)
        if node.function == "copysign":  # |a| carries the sign of b, a constant
            return copysign(1.0, a) * copysign(1.0, node.arguments[1]) * d
        raise GenerationError(f"no derivative of {node.function}()")

    def _d_Lookup(self, node):
        if node.slope:
            raise GenerationError(f"no derivative of the slope of {node.table}")
        d = self.of(node.argument)
        return None if d is None else Lookup(node.table, node.argument, slope=True) * d


# --- printers -----------------------------------------------------------------------------

class Printer:
    """Prints trees as text. A language subclass sets the precedence table and the
    spelling of what differs; printing a function body keeps track of the names it
    knows, so a name read before it is assigned is an error here."""

    # Binding strength: a child weaker than its parent is parenthesized.
    CONDITIONAL, OR, AND, NOT, COMPARE, ADD, MULTIPLY, UNARY, ATOM = range(1, 10)
    BINARY = {"+": ADD, "-": ADD, "*": MULTIPLY, "/": MULTIPLY}

    def __init__(self, known=(), constants=()):
        self.known = set(known) | set(constants)
        self.constants = set(constants)  # parameters and derived constants: never assigned

    def expression(self, node):
        return self._print(node)[0]

    def _print(self, node):
        """(text, precedence) of a node."""
        method = getattr(self, f"_print_{type(node).__name__}", None)
        if method is None:
            raise GenerationError(f"{type(self).__name__} cannot print {type(node).__name__}")
        return method(node)

    def _operand(self, node, minimum):
        """A child's text, parenthesized unless it binds at least as strongly as `minimum`."""
        text, precedence = self._print(node)
        return text if precedence >= minimum else f"({text})"

    def _print_Number(self, node):
        text = repr(node.value)
        return text, self.UNARY if text.startswith("-") else self.ATOM

    def _print_Symbol(self, node):
        if node.name not in self.known:
            raise GenerationError(f"{node.name!r} is read before it is given a value")
        return self.symbol(node.name), self.ATOM

    def symbol(self, name):
        return name

    def _print_Element(self, node):
        return f"{node.array}[{node.index}]", self.ATOM

    def _print_Negate(self, node):
        # -(-a), never --a (a decrement in C)
        return f"-{self._operand(node.operand, self.ATOM)}", self.UNARY

    def _print_Binary(self, node):
        level = self.BINARY[node.op]
        # left-associative: a - (b - c) keeps its parentheses, (a - b) - c needs none
        return (f"{self._operand(node.left, level)} {node.op} "
                f"{self._operand(node.right, level + 1)}", level)

    def _print_Compare(self, node):
        return (f"{self._operand(node.left, self.ADD)} {node.op} "
                f"{self._operand(node.right, self.ADD)}", self.COMPARE)

    def _print_Absolute(self, node):
        # |a| of a name as a conditional (no call: faster in CPython); of anything else,
        # the library's absolute value. Both printers choose alike, so the sign of a zero
        # result is the same in both languages.
        if isinstance(node.operand, (Symbol, Element)):
            a = self.expression(node.operand)
            return self.conditional(f"{a} >= 0.0", a, f"-{a}"), self.ATOM
        return f"{self.ABSOLUTE}({self.expression(node.operand)})", self.ATOM

    def _print_Call(self, node):
        arguments = ", ".join(self.expression(a) for a in node.arguments)
        return f"{node.function}({arguments})", self.ATOM

    def _print_Conditional(self, node):
        return self.conditional(self._operand(node.test, self.OR),
                                self._operand(node.then, self.OR),
                                self._operand(node.otherwise, self.OR)), self.ATOM

    # --- statements ---------------------------------------------------------------------

    def statements(self, nodes, fail):
        """Lines for a body of statements; `fail` is the line a failed Require runs."""
        lines = []
        for node in nodes:
            if isinstance(node, Assign):
                value = self.expression(node.value)
                lines.append(self.assignment(node.target, value))
            elif isinstance(node, Require):
                lines += self.requirement(self.expression(node.test), fail)
            else:
                raise GenerationError(f"{type(self).__name__} cannot print {node!r}")
        return lines

    def assignment(self, target, value):
        if isinstance(target, Symbol):
            if target.name in self.constants:
                raise GenerationError(f"{target.name!r} is a parameter or constant; a local "
                                      f"may not take its name")
            self.known.add(target.name)
        return f"{self.expression(target)} = {value}"


class PythonPrinter(Printer):
    """Straight-line Python. Parameters and derived constants are printed as literals
    (``literals``: name -> value), which CPython loads fastest."""

    ABSOLUTE = "abs"

    def __init__(self, literals, known=()):
        super().__init__(known, literals)
        self.literals = literals

    def symbol(self, name):
        value = self.literals.get(name)
        if value is None:
            return name
        text = repr(float(value))
        return f"({text})" if text.startswith("-") else text

    def _print_Logical(self, node):
        level = self.AND if node.op == "and" else self.OR
        return (f"{self._operand(node.left, level)} {node.op} "
                f"{self._operand(node.right, level + 1)}", level)

    def _print_Not(self, node):
        return f"not {self._operand(node.operand, self.NOT)}", self.NOT

    def _print_Lookup(self, node):
        part = "slope" if node.slope else "value"
        return f"{node.table}_{part}({self.expression(node.argument)})", self.ATOM

    @staticmethod
    def conditional(test, then, otherwise):
        return f"({then} if {test} else {otherwise})"

    @staticmethod
    def requirement(test, fail):
        return [f"if not ({test}):", f"    {fail}"]

    def message(self, message):
        """An f-string."""
        text = []
        for part in message.parts:
            if isinstance(part, Format):
                text.append(f"{{{self.expression(part.value)}:{part.spec}}}")
            else:
                text.append(part.replace("{", "{{").replace("}", "}}"))
        return "f" + repr("".join(text))
