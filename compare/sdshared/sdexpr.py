"""sdexpr — the sdcrack scene expression grammar in Python: ONE parser, three back-ends.

This is a port of ``crates/sdcrack-core/src/expr.rs`` (grammar, precedence and error messages/columns), used by
the reference solvers so that a scene string means the same function everywhere (translate, never
re-type).

Grammar (identical to the Rust one)::

    expr    := term   (('+' | '-') term)*          left-associative
    term    := unary  (('*' | '/') unary)*         left-associative
    unary   := ('+' | '-')* power                  signs bind looser than '^'
    power   := primary ('^' unary)?                right-associative
    primary := number | 'x' | 'y' | 'pi' | '(' expr ')'
             | func1 '(' expr ')' | func2 '(' expr ',' expr ')'
    func1   := sin | cos | tan | exp | log | sqrt | abs | sign
    func2   := atan2 | min | max
    number  := digits ['.' digits] | '.' digits, optionally followed by (e|E)[+|-]digits

So ``-x^2 == -(x^2)``, ``2^3^2 == 2^(3^2) == 512`` and ``2^-x == 2^(-x)``. ``log`` is the natural
logarithm; ``atan2(a, b)`` is the angle of the point (b, a).

Signed zero: ``sign(v)`` is 1 for v > 0, -1 for v < 0 and ``copysign(1, v)`` for v = +-0.0, so
evaluating with ``y = +0.0`` / ``y = -0.0`` selects the + / - face of a crack lying on y = 0
(``atan2`` already respects signed zero).

Trees are nested tuples:
    ('num', v) | ('x',) | ('y',) | ('neg', a) | (op, a, b) with op in '+-*/^'
    | ('f1', name, a) | ('f2', name, a, b)

Back-ends:
    to_numpy(tree)    -> f(x, y) on numpy arrays (or floats)
    to_ufl(tree, x)   -> UFL expression, x = ufl.SpatialCoordinate(mesh)
    to_freefem(tree)  -> FreeFEM++ expression string in x, y (fully parenthesised)

FreeFEM caveat: FreeFEM has no signed zeros in practice (and no ``sign``; it is rendered as
``((a) >= 0 ? 1. : -1.)``), so on a crack line the value of a side-dependent expression is NOT
selected by the sign of y. A caller that needs one face's value must evaluate at points strictly
inside the triangles of that face (e.g. quadrature points), never at crack vertices.
UFL caveat: ``ufl.sign(0) = 0``; UFL expressions are meant to be evaluated at quadrature points,
which are interior to cells, so the sign of zero never matters there.
"""

import math
import sys

__all__ = ["ExprError", "parse", "to_numpy", "to_ufl", "to_freefem", "evaluate", "FUNC1", "FUNC2"]

MAX_LEN = 10000
MAX_DEPTH = 200
FUNC1 = ("sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sign")
FUNC2 = ("atan2", "min", "max")
FUNC_NAMES = FUNC1 + FUNC2


class ExprError(ValueError):
    """A parse error: ``message`` and 1-based ``column``."""

    def __init__(self, message, column):
        super().__init__(f"column {column}: {message}")
        self.message = message
        self.column = column


# ---------------------------------------------------------------------------------------------
# Lexer
# ---------------------------------------------------------------------------------------------

class _Tok:
    __slots__ = ("kind", "value", "col", "text")

    def __init__(self, kind, col, text, value=None):
        self.kind = kind  # 'num' 'ident' '+' '-' '*' '/' '^' '(' ')' ',' 'bad' 'end'
        self.value = value  # float for num, name for ident, ExprError for bad
        self.col = col
        self.text = text


def _lex(src):
    toks = []
    i, n = 0, len(src)
    while i < n:
        c = src[i]
        col = i + 1
        if c.isspace():
            i += 1
            continue
        if c in "+-*/^(),":
            toks.append(_Tok(c, col, c))
            i += 1
            continue

        def digit_at(k):
            return k < n and src[k] in "0123456789"

        if c in "0123456789" or (c == "." and digit_at(i + 1)):
            start = i
            while digit_at(i):
                i += 1
            if i < n and src[i] == ".":
                i += 1
                while digit_at(i):
                    i += 1
            if i < n and src[i] in "eE":
                k = i + 1
                if k < n and src[k] in "+-":
                    k += 1
                if digit_at(k):
                    i = k
                    while digit_at(i):
                        i += 1
            text = src[start:i]
            try:
                v = float(text)
            except ValueError:
                toks.append(_Tok("bad", col, text, ExprError(f"malformed number '{text}'", col)))
                break
            if not math.isfinite(v):
                toks.append(_Tok("bad", col, text, ExprError(
                    f"number '{text}' is too large (overflows to infinity)", col)))
                break
            toks.append(_Tok("num", col, text, v))
            continue
        if (c.isascii() and c.isalpha()) or c == "_":
            start = i
            while i < n and ((src[i].isascii() and src[i].isalnum()) or src[i] == "_"):
                i += 1
            text = src[start:i]
            toks.append(_Tok("ident", col, text, text))
            continue
        toks.append(_Tok("bad", col, c, ExprError(f"unexpected character '{c}'", col)))
        break
    toks.append(_Tok("end", n + 1, "end of input"))
    return toks


def _levenshtein(a, b):
    prev = list(range(len(b) + 1))
    for i, ca in enumerate(a):
        cur = [i + 1] + [0] * len(b)
        for j, cb in enumerate(b):
            cur[j + 1] = min(prev[j] + (ca != cb), prev[j + 1] + 1, cur[j] + 1)
        prev = cur
    return prev[len(b)]


def _suggest(name, candidates):
    if len(name) > 12:
        return None
    lower = name.lower()
    best = None
    for c in candidates:
        d = _levenshtein(lower, c)
        if best is None or d < best[0]:
            best = (d, c)
    limit = 2 if len(name) >= 4 else 1
    return best[1] if best[0] <= limit else None


# ---------------------------------------------------------------------------------------------
# Parser
# ---------------------------------------------------------------------------------------------

class _Parser:
    def __init__(self, toks):
        self.toks = toks
        self.pos = 0
        self.depth = 0

    def peek(self):
        return self.toks[min(self.pos, len(self.toks) - 1)]

    def peek2(self):
        return self.toks[min(self.pos + 1, len(self.toks) - 1)]

    def advance(self):
        t = self.peek()
        if t.kind not in ("end", "bad"):
            self.pos += 1
        return t

    def enter(self, col):
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExprError(f"expression nested deeper than {MAX_DEPTH} levels", col)

    def leave(self):
        self.depth -= 1

    def expr(self):
        return self.left_associative(("+", "-"), self.term)

    def term(self):
        return self.left_associative(("*", "/"), self.unary)

    def left_associative(self, ops, operand):
        """operand (op operand)* for op in `ops`, grouped to the left: a − b − c = (a − b) − c."""
        node = operand()
        while self.peek().kind in ops:
            op = self.advance().kind
            node = (op, node, operand())
        return node

    def unary(self):
        negative = False
        while self.peek().kind in ("+", "-"):
            if self.advance().kind == "-":
                negative = not negative
        operand = self.power()
        return ("neg", operand) if negative else operand

    def power(self):
        base = self.primary()
        if self.peek().kind == "^":
            caret = self.advance()
            self.enter(caret.col)
            exponent = self.unary()
            self.leave()
            return ("^", base, exponent)
        return base

    def missing_operand(self, t):
        if t.kind == "bad":
            return t.value
        if self.pos >= 1:
            p = self.toks[self.pos - 1]
            if p.kind in ("+", "-", "*", "/", "^"):
                return ExprError(f"missing operand after '{p.text}'", p.col)
            if p.kind == ",":
                return ExprError("missing argument after ','", p.col)
            if p.kind == "(" and t.kind == ")":
                return ExprError("empty parentheses", p.col)
            if p.kind == "(" and t.kind == "end":
                return ExprError("unclosed parenthesis", p.col)
        if t.kind == ")":
            return ExprError("unmatched ')'", t.col)
        return ExprError(f"expected an operand, found '{t.text}'", t.col)

    def expect_close(self, open_col):
        t = self.peek()
        if t.kind == ")":
            self.advance()
            return
        if t.kind == "end":
            raise ExprError("unclosed parenthesis", open_col)
        if t.kind == "bad":
            raise t.value
        raise ExprError(f"expected ')' or an operator, found '{t.text}'", t.col)

    def primary(self):
        t = self.peek()
        if t.kind == "num":
            self.advance()
            return ("num", t.value)
        if t.kind == "(":
            self.advance()
            self.enter(t.col)
            e = self.expr()
            self.expect_close(t.col)
            self.leave()
            return e
        if t.kind == "ident":
            name = t.value
            if self.peek2().kind == "(":
                return self.call(t, name)
            self.advance()
            if name == "x":
                return ("x",)
            if name == "y":
                return ("y",)
            if name == "pi":
                return ("num", math.pi)
            if name in FUNC_NAMES:
                raise ExprError(f"function '{name}' must be followed by '(' and its arguments", t.col)
            low = name.lower()
            hint = f"did you mean '{low}'?" if low in ("x", "y", "pi") else "expected x, y or pi"
            raise ExprError(f"unknown variable '{name}' ({hint})", t.col)
        raise self.missing_operand(t)

    def call(self, name_tok, name):
        if name in FUNC1:
            arity = 1
        elif name in FUNC2:
            arity = 2
        else:
            if name in ("x", "y", "pi"):
                msg = f"'{name}' is a variable, not a function (write '{name}*(...)')"
            else:
                s = _suggest(name, FUNC_NAMES)
                msg = f"unknown function '{name}'" + (f" (did you mean '{s}'?)" if s else "")
            raise ExprError(msg, name_tok.col)
        self.advance()  # name
        open_tok = self.advance()  # '('
        self.enter(open_tok.col)
        args = []
        if self.peek().kind == ")":
            self.advance()
        else:
            while True:
                args.append(self.expr())
                t = self.peek()
                if t.kind == ",":
                    self.advance()
                elif t.kind == ")":
                    self.advance()
                    break
                elif t.kind == "end":
                    raise ExprError("unclosed parenthesis", open_tok.col)
                elif t.kind == "bad":
                    raise t.value
                else:
                    raise ExprError(f"expected ',' or ')' or an operator, found '{t.text}'", t.col)
        self.leave()
        if len(args) != arity:
            plural = "argument" if arity == 1 else "arguments"
            raise ExprError(f"{name} takes {arity} {plural}, got {len(args)}", name_tok.col)
        if arity == 1:
            return ("f1", name, args[0])
        return ("f2", name, args[0], args[1])


def parse(src):
    """Parse an expression string into a tree; raises ExprError(message, column)."""
    if not isinstance(src, str):
        raise ExprError(f"expression must be a string, got {type(src).__name__}", 1)
    if len(src) > MAX_LEN:
        raise ExprError(f"expression longer than {MAX_LEN} characters ({len(src)} characters)",
                        MAX_LEN + 1)
    if src.strip() == "":
        raise ExprError("empty expression", 1)
    p = _Parser(_lex(src))
    # MAX_DEPTH levels need ~7 Python frames each: make sure the limit check fires first.
    old_limit = sys.getrecursionlimit()
    if old_limit < 20 * MAX_DEPTH:
        sys.setrecursionlimit(20 * MAX_DEPTH)
    try:
        node = p.expr()
    finally:
        sys.setrecursionlimit(old_limit)
    t = p.peek()
    if t.kind == "end":
        return node
    if t.kind == "bad":
        raise t.value
    if t.kind == ")":
        raise ExprError("unmatched ')'", t.col)
    raise ExprError(f"unexpected trailing input '{t.text}'", t.col)


def _tree(t):
    return parse(t) if isinstance(t, str) else t


# ---------------------------------------------------------------------------------------------
# numpy back-end
# ---------------------------------------------------------------------------------------------

def _np_sign(np, v):
    # 1 for v > 0, -1 for v < 0, copysign(1, v) for +-0, NaN for NaN.
    return np.where(np.isnan(v), np.nan, np.copysign(1.0, v))


def to_numpy(tree):
    """Return f(x, y) evaluating the tree on numpy arrays (broadcasting; result is a float array)."""
    import numpy as np

    tree = _tree(tree)
    f1 = {
        "sin": np.sin, "cos": np.cos, "tan": np.tan, "exp": np.exp, "log": np.log,
        "sqrt": np.sqrt, "abs": np.abs, "sign": lambda v: _np_sign(np, v),
    }
    # Rust f64::min/max ignore a NaN operand: numpy fmin/fmax do the same.
    f2 = {"atan2": np.arctan2, "min": np.fmin, "max": np.fmax}
    binop = {
        "+": np.add, "-": np.subtract, "*": np.multiply, "/": np.divide, "^": np.power,
    }

    def build(n):
        k = n[0]
        if k == "num":
            v = n[1]
            return lambda x, y: v
        if k == "x":
            return lambda x, y: x
        if k == "y":
            return lambda x, y: y
        if k == "neg":
            a = build(n[1])
            return lambda x, y: np.negative(a(x, y))
        if k in binop:
            op, a, b = binop[k], build(n[1]), build(n[2])
            return lambda x, y: op(a(x, y), b(x, y))
        if k == "f1":
            fn, a = f1[n[1]], build(n[2])
            return lambda x, y: fn(a(x, y))
        if k == "f2":
            fn, a, b = f2[n[1]], build(n[2]), build(n[3])
            return lambda x, y: fn(a(x, y), b(x, y))
        raise ValueError(f"bad node {n!r}")

    g = build(tree)

    def f(x, y):
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        with np.errstate(all="ignore"):
            r = g(x, y)
        return np.broadcast_to(np.asarray(r, dtype=float), np.broadcast(x, y).shape).copy()

    return f


def evaluate(tree, x, y):
    """Scalar evaluation with Python's math module (reference semantics, NaN instead of errors)."""
    tree = _tree(tree)

    def ev(n):
        k = n[0]
        if k == "num":
            return n[1]
        if k == "x":
            return float(x)
        if k == "y":
            return float(y)
        if k == "neg":
            return -ev(n[1])
        if k in "+-*/^" and len(k) == 1:
            a, b = ev(n[1]), ev(n[2])
            try:
                if k == "+":
                    return a + b
                if k == "-":
                    return a - b
                if k == "*":
                    return a * b
                if k == "/":
                    if b == 0.0:
                        if a == 0.0 or math.isnan(a):
                            return math.nan
                        return math.copysign(math.inf, a) * math.copysign(1.0, b)
                    return a / b
                return math.pow(a, b)
            except (ValueError, OverflowError):
                return math.nan
        if k == "f1":
            a = ev(n[2])
            name = n[1]
            if name == "sign":
                return math.nan if math.isnan(a) else math.copysign(1.0, a)
            if name == "abs":
                return abs(a)
            try:
                return getattr(math, name)(a)
            except (ValueError, OverflowError):
                if name == "log" and a == 0.0:
                    return -math.inf
                if name == "exp":
                    return math.inf
                return math.nan
        if k == "f2":
            a, b = ev(n[2]), ev(n[3])
            if n[1] == "atan2":
                return math.atan2(a, b)
            if math.isnan(a):
                return b
            if math.isnan(b):
                return a
            return min(a, b) if n[1] == "min" else max(a, b)
        raise ValueError(f"bad node {n!r}")

    return ev(tree)


# ---------------------------------------------------------------------------------------------
# UFL back-end
# ---------------------------------------------------------------------------------------------

def on_face(x, y, normal, side):
    """Coordinates of crack points as seen from face `side` (+1: the side ν points into), the rule
    of eval_on_face (crates/sdcrack-core/src/problem.rs): exactly-zero coordinates get the sign of side·ν (IEEE
    signed zero), so that ``to_numpy`` of ``sign``/``atan2`` selects that face."""
    import numpy as np

    x, y = np.array(x, dtype=float), np.array(y, dtype=float)
    for c, nu in ((x, normal[0]), (y, normal[1])):
        if nu != 0.0:
            c[c == 0.0] = np.copysign(0.0, side * nu)
    return x, y


def to_ufl(tree, x):
    """UFL expression of the tree; ``x = ufl.SpatialCoordinate(mesh)`` (x[0] = x, x[1] = y)."""
    import ufl

    tree = _tree(tree)
    f1 = {
        "sin": ufl.sin, "cos": ufl.cos, "tan": ufl.tan, "exp": ufl.exp, "log": ufl.ln,
        "sqrt": ufl.sqrt, "abs": abs, "sign": ufl.sign,
    }
    f2 = {"atan2": ufl.atan_2, "min": ufl.min_value, "max": ufl.max_value}

    def build(n):
        k = n[0]
        if k == "num":
            return ufl.as_ufl(float(n[1]))
        if k == "x":
            return x[0]
        if k == "y":
            return x[1]
        if k == "neg":
            return -build(n[1])
        if k == "+":
            return build(n[1]) + build(n[2])
        if k == "-":
            return build(n[1]) - build(n[2])
        if k == "*":
            return build(n[1]) * build(n[2])
        if k == "/":
            return build(n[1]) / build(n[2])
        if k == "^":
            return build(n[1]) ** build(n[2])
        if k == "f1":
            return f1[n[1]](build(n[2]))
        if k == "f2":
            return f2[n[1]](build(n[2]), build(n[3]))
        raise ValueError(f"bad node {n!r}")

    return build(tree)


# ---------------------------------------------------------------------------------------------
# FreeFEM back-end
# ---------------------------------------------------------------------------------------------

def _ff_num(v):
    if v == math.pi:
        return "pi"
    s = repr(float(v))  # shortest round-trip; always has '.' or 'e' (never integer division)
    if "inf" in s or "nan" in s:
        raise ValueError(f"cannot render {s} in FreeFEM")
    return f"({s})" if v < 0 or s.startswith("-") else s


def to_freefem(tree):
    """FreeFEM++ expression string in x, y, fully parenthesised.

    ``sign(a)`` becomes ``((a) >= 0 ? 1. : -1.)``: FreeFEM cannot distinguish -0.0 from +0.0, so
    on a crack line the face must be chosen by the caller evaluating at interior points.
    """
    tree = _tree(tree)

    def r(n):
        k = n[0]
        if k == "num":
            return _ff_num(n[1])
        if k in ("x", "y"):
            return k
        if k == "neg":
            return f"(-{r(n[1])})"
        if k in ("+", "-", "*", "/", "^"):
            return f"({r(n[1])} {k} {r(n[2])})"
        if k == "f1":
            if n[1] == "sign":
                return f"(({r(n[2])}) >= 0 ? 1. : -1.)"
            return f"{n[1]}({r(n[2])})"
        if k == "f2":
            return f"{n[1]}({r(n[2])}, {r(n[3])})"
        raise ValueError(f"bad node {n!r}")

    return r(tree)


# ---------------------------------------------------------------------------------------------
# Symbolic derivative
# ---------------------------------------------------------------------------------------------

def _d_is_num(n, v=None):
    return n[0] == "num" and (v is None or n[1] == v)


def _d_is_const(n):
    k = n[0]
    if k == "num":
        return True
    if k in ("x", "y"):
        return False
    if k == "f1":
        return _d_is_const(n[2])
    if k == "f2":
        return _d_is_const(n[2]) and _d_is_const(n[3])
    return all(_d_is_const(c) for c in n[1:])


def _d_fold(v, fallback):
    """A folded constant when finite, else the unfolded node (so 1/0 stays an expression)."""
    return ("num", float(v)) if isinstance(v, float) and math.isfinite(v) else fallback


def _d_neg(a):
    if a[0] == "num":
        return ("num", -a[1])
    if a[0] == "neg":
        return a[1]
    return ("neg", a)


def _d_add(a, b):
    if _d_is_num(a, 0.0):
        return b
    if _d_is_num(b, 0.0):
        return a
    if a[0] == "num" and b[0] == "num":
        return _d_fold(a[1] + b[1], ("+", a, b))
    return ("+", a, b)


def _d_sub(a, b):
    if _d_is_num(b, 0.0):
        return a
    if _d_is_num(a, 0.0):
        return _d_neg(b)
    if a[0] == "num" and b[0] == "num":
        return _d_fold(a[1] - b[1], ("-", a, b))
    return ("-", a, b)


def _d_mul(a, b):
    # 0*a -> 0 even for a non-finite a: the Rust simplifier folds the same way.
    if _d_is_num(a, 0.0) or _d_is_num(b, 0.0):
        return ("num", 0.0)
    if _d_is_num(a, 1.0):
        return b
    if _d_is_num(b, 1.0):
        return a
    if _d_is_num(a, -1.0):
        return _d_neg(b)
    if _d_is_num(b, -1.0):
        return _d_neg(a)
    if a[0] == "num" and b[0] == "num":
        return _d_fold(a[1] * b[1], ("*", a, b))
    return ("*", a, b)


def _d_div(a, b):
    if _d_is_num(a, 0.0):
        return ("num", 0.0)
    if _d_is_num(b, 1.0):
        return a
    if a[0] == "num" and b[0] == "num" and b[1] != 0.0:
        return _d_fold(a[1] / b[1], ("/", a, b))
    return ("/", a, b)


def _d_pow(a, b):
    if _d_is_num(b, 1.0):
        return a
    if _d_is_num(b, 0.0):
        return ("num", 1.0)
    if a[0] == "num" and b[0] == "num":
        try:
            v = math.pow(a[1], b[1])
        except (ValueError, OverflowError):
            v = math.nan
        return _d_fold(v, ("^", a, b))
    return ("^", a, b)


def _d_f1(name, a):
    if a[0] == "num":
        return _d_fold(evaluate(("f1", name, a), 0.0, 0.0), ("f1", name, a))
    return ("f1", name, a)


def _d_select(a, b, c, d):
    """``c if a < b else d`` in the tree forms (no conditional node exists):
    c*((1 - s)/2) + d*((1 + s)/2) with s = sign((a - b) + 0). Adding +0 turns a difference of
    -0 into +0, so a == b (ties, signed zeros included) gives s = 1 and selects d exactly like
    the Rust ``a < b`` test. Exact whenever the unselected branch is finite (0*inf is NaN), and
    NaN where a - b is NaN (Rust selects d there); the same caveats as the Rust infix rendering."""
    if c == d:
        return c
    s = ("f1", "sign", ("+", _d_sub(a, b), ("num", 0.0)))
    lo = _d_mul(c, _d_div(_d_sub(("num", 1.0), s), ("num", 2.0)))
    hi = _d_mul(d, _d_div(_d_add(("num", 1.0), s), ("num", 2.0)))
    return _d_add(lo, hi)


def _deriv(n, var):
    k = n[0]
    if k == "num":
        return ("num", 0.0)
    if k in ("x", "y"):
        return ("num", 1.0 if k == var else 0.0)
    if k == "neg":
        return _d_neg(_deriv(n[1], var))
    if k == "f1":
        return _deriv_f1(n[1], n[2], var)
    if k == "f2":
        return _deriv_f2(n[1], n[2], n[3], var)
    a, b = n[1], n[2]
    if k == "+":
        return _d_add(_deriv(a, var), _deriv(b, var))
    if k == "-":
        return _d_sub(_deriv(a, var), _deriv(b, var))
    if k == "*":
        return _d_add(_d_mul(_deriv(a, var), b), _d_mul(a, _deriv(b, var)))
    if k == "/":
        # (a/b)' = a'/b - a*b'/b/b (as the Rust quotient rule: two divisions, no b^2)
        return _d_sub(_d_div(_deriv(a, var), b), _d_div(_d_div(_d_mul(a, _deriv(b, var)), b), b))
    if k == "^":
        return _deriv_pow(a, b, var)
    raise ValueError(f"bad node {n!r}")


def _deriv_pow(a, b, var):
    da = _deriv(a, var)
    if _d_is_const(b):
        # b * a^(b-1) * a'
        return _d_mul(_d_mul(b, _d_pow(a, _d_sub(b, ("num", 1.0)))), da)
    db = _deriv(b, var)
    p = _d_pow(a, b)
    if _d_is_const(a):
        return _d_mul(_d_mul(p, _d_f1("log", a)), db)
    # a^b * (b'*log(a) + b*a'/a)
    return _d_mul(p, _d_add(_d_mul(db, _d_f1("log", a)), _d_div(_d_mul(b, da), a)))


def _deriv_f1(name, a, var):
    da = _deriv(a, var)
    if _d_is_num(da, 0.0) or name == "sign":
        return ("num", 0.0)  # sign' = 0 (also at 0, as in Rust)
    if name == "sin":
        outer = _d_f1("cos", a)
    elif name == "cos":
        outer = _d_neg(_d_f1("sin", a))
    elif name == "tan":
        outer = _d_div(("num", 1.0), _d_pow(_d_f1("cos", a), ("num", 2.0)))
    elif name == "exp":
        outer = _d_f1("exp", a)
    elif name == "log":
        outer = _d_div(("num", 1.0), a)
    elif name == "sqrt":
        outer = _d_div(("num", 0.5), _d_f1("sqrt", a))
    elif name == "abs":
        outer = _d_f1("sign", a)  # abs' = sign (sign(+0) = 1)
    else:
        raise ValueError(f"bad function {name!r}")
    return _d_mul(outer, da)


def _deriv_f2(name, a, b, var):
    da, db = _deriv(a, var), _deriv(b, var)
    if name == "atan2":
        # (b*a' - a*b') / (a^2 + b^2)
        numer = _d_sub(_d_mul(b, da), _d_mul(a, db))
        denom = _d_add(_d_pow(a, ("num", 2.0)), _d_pow(b, ("num", 2.0)))
        return _d_div(numer, denom)
    if name == "min":
        return _d_select(a, b, da, db)  # a < b: a' ; ties: the second argument's
    if name == "max":
        return _d_select(a, b, db, da)  # a < b: b' ; ties: the first argument's
    raise ValueError(f"bad function {name!r}")


def derivative(tree, var):
    """The symbolic derivative of ``tree`` (a tree or a source string) by ``var`` ("x" or "y"),
    as a tree of the same forms, lightly simplified (0*a -> 0, 1*a -> a, a+0 -> a, folding of
    finite constants). Conventions of ``Expr::derivative`` in crates/sdcrack-core/src/expr.rs:
    sign' = 0 everywhere, abs(a)' = sign(a)*a', min/max take the derivative of the active
    argument (``a < b`` decides; ties: the second argument's for min, the first's for max),
    (a^b)' = b*a^(b-1)*a' when b is constant, a^b*log(a)*b' when a is constant, else
    a^b*(b'*log(a) + b*a'/a); atan2(a, b)' = (b*a' - a*b')/(a^2 + b^2); sqrt(a)' = 0.5/sqrt(a)*a'.
    The min/max selection is written with sign() (see ``_d_select``): exact wherever the
    unselected branch's derivative is finite."""
    if var not in ("x", "y"):
        raise ValueError(f"derivative variable must be 'x' or 'y', got {var!r}")
    tree = _tree(tree)
    old_limit = sys.getrecursionlimit()
    if old_limit < 40 * MAX_DEPTH:
        sys.setrecursionlimit(40 * MAX_DEPTH)
    try:
        return _deriv(tree, var)
    finally:
        sys.setrecursionlimit(old_limit)


__all__.append("derivative")
