"""LaTeX text helpers of the report: escaping names, numbers, a sympy printer, widths and line
breaking.

Every expression reaches the report through :class:`Tex`, a sympy ``LatexPrinter``; long ones are
broken over the lines of an ``align*`` by :meth:`Tex.lines` (sums split between terms, products,
fractions and function arguments opened with ``\\Bigl( ... \\Bigr)``) so that nothing runs off a
page of :data:`LINE_WIDTH_EM` ems (a one-column article's 345 pt text width at 10 pt).
"""

from __future__ import annotations

import decimal
import math
import re
import unicodedata
from collections.abc import Iterable, Mapping
from functools import lru_cache

import sympy as sp
from sympy.printing.latex import LatexPrinter

from ..codegen.literals import fold_numbers
from ..model import special

#: Width the equations are broken for, in ems of the 10 pt body font (345 pt = article's
#: one-column \textwidth; the standalone report is wider, an appendix may be this narrow).
LINE_WIDTH_EM = 31.0
#: Width reserved for the left side of an align line (a longer left side takes its own width).
LHS_EM = 5.0

# -- escaping ------------------------------------------------------------------------------------

_TEXT_SPECIALS = {
    # typewriter glyphs (OT1 cmtt has the ASCII layout): literal, and no TS1 bitmap fonts
    "\\": r"{\ttfamily\char92}",
    "{": r"{\ttfamily\char123}",
    "}": r"{\ttfamily\char125}",
    "$": r"{\ttfamily\char36}",
    "^": r"{\ttfamily\char94}",
    "~": r"{\ttfamily\char126}",
    "<": r"{\ttfamily\char60}",
    ">": r"{\ttfamily\char62}",
    "|": r"{\ttfamily\char124}",
    '"': r"{\ttfamily\char34}",
    "&": r"\&",
    "#": r"\#",
    "%": r"\%",
    "_": r"\_\penalty0{}",
    "/": r"/\penalty0{}",
    # characters that would form ligatures (--, ``, '', !`, ?`) are kept apart
    "-": "-{}",
    "`": "`{}",
    "'": "'{}",
    "!": "!{}",
    "?": "?{}",
}

_ACCENTS = {
    "\u0300": "`",
    "\u0301": "'",
    "\u0302": "^",
    "\u0303": "~",
    "\u0304": "=",
    "\u0306": "u",
    "\u0307": ".",
    "\u0308": '"',
    "\u030a": "r",
    "\u030b": "H",
    "\u030c": "v",
    "\u0327": "c",
}

_LETTERS = {
    "ß": r"\ss{}",
    "æ": r"\ae{}",
    "Æ": r"\AE{}",
    "ø": r"\o{}",
    "Ø": r"\O{}",
    "œ": r"\oe{}",
    "Œ": r"\OE{}",
    "ł": r"\l{}",
    "Ł": r"\L{}",
    "ı": r"\i{}",
    "µ": r"\ensuremath{\mu}",
    "°": r"\ensuremath{^\circ}",
    "×": r"\ensuremath{\times}",
    "±": r"\ensuremath{\pm}",
}


def _non_ascii(ch: str) -> str:
    if ch in _LETTERS:
        return _LETTERS[ch]
    name = unicodedata.name(ch, "")
    greek = re.fullmatch(r"GREEK (SMALL|CAPITAL) LETTER ([A-Z]+)", name)
    if greek:
        word = greek.group(2).lower()
        if greek.group(1) == "CAPITAL":
            word = word.capitalize()
        known = {
            "alpha",
            "beta",
            "gamma",
            "delta",
            "epsilon",
            "zeta",
            "eta",
            "theta",
            "iota",
            "kappa",
            "lambda",
            "mu",
            "nu",
            "xi",
            "pi",
            "rho",
            "sigma",
            "tau",
            "upsilon",
            "phi",
            "chi",
            "psi",
            "omega",
            "Gamma",
            "Delta",
            "Theta",
            "Lambda",
            "Xi",
            "Pi",
            "Sigma",
            "Upsilon",
            "Phi",
            "Psi",
            "Omega",
        }
        if word in known:
            return rf"\ensuremath{{\{word}}}"
    decomposed = unicodedata.normalize("NFD", ch)
    base, marks = decomposed[:1], decomposed[1:]
    if base.isascii() and base.isalpha() and marks and len(marks) == 1 and marks in _ACCENTS:
        letter = r"\i" if base == "i" else base
        return rf"\{_ACCENTS[marks]}{{{letter}}}"
    return rf"\texttt{{[U+{ord(ch):04X}]}}"


def escape_latex(text: str) -> str:
    """`text` as literal LaTeX text (text mode; inside math wrap it in ``\\text{}``).

    TeX's special characters become their text commands, characters that form ligatures are kept
    apart, control characters and unknown non-ASCII characters become a visible ``[U+XXXX]``, so
    no name can run a command, open a group, start math or comment out the rest of a line.
    """
    out = []
    for ch in str(text):
        code = ord(ch)
        if ch in _TEXT_SPECIALS:
            out.append(_TEXT_SPECIALS[ch])
        elif 32 <= code < 127:
            out.append(ch)
        elif code < 32 or 127 <= code < 160:
            out.append(rf"\texttt{{[U+{code:04X}]}}")
        else:
            out.append(_non_ascii(ch))
    return "".join(out)


def math_name(text: str) -> str:
    """A name from the mechanism file for use inside math mode."""
    return r"\text{" + escape_latex(text) + "}"


def plain_name(text: str) -> str:
    """A name for matplotlib text drawn without math parsing: control characters replaced."""
    return "".join(ch if ch.isprintable() else "?" for ch in str(text))


# -- numbers -------------------------------------------------------------------------------------


def sci(x: float, digits: int = 3) -> str:
    r"""A float as LaTeX math text: ``1.23\times 10^{-6}`` (or plain for moderate magnitudes)."""
    if x is None or not math.isfinite(x):
        return r"\text{--}"
    if x == 0:
        return "0"
    exponent = math.floor(math.log10(abs(x)))
    if -2 <= exponent <= 3:
        return f"{x:.{max(digits - 1 - exponent, 0)}f}"
    mantissa = x / 10**exponent
    text = f"{mantissa:.{digits - 1}f}"
    if text.startswith(("10.", "-10.")):
        mantissa /= 10
        exponent += 1
        text = f"{mantissa:.{digits - 1}f}"
    return rf"{text}\times 10^{{{exponent}}}"


def gnum(x: float) -> str:
    """A float with up to 6 significant digits as LaTeX math text."""
    text = f"{x:.6g}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        lead = "" if mantissa == "1" else mantissa + r"\times "
        return rf"{lead}10^{{{int(exponent)}}}"
    return text


# -- the printer ---------------------------------------------------------------------------------

#: How the report writes the elastica functions (kernels: see :func:`special_symbol`).
_ELASTICA_SYMBOLS = {
    "elastica_x": r"X_{e}",
    "elastica_y": r"Y_{e}",
    "elastica_dx": r"\Delta X_{e}",
    "elastica_dy": r"\Delta Y_{e}",
    "elastica_dx_d1": r"\Delta X_{e}'",
    "elastica_dy_d1": r"\Delta Y_{e}'",
}


def special_symbol(name: str) -> str:
    """The report's symbol of a special function: s_n, c_n, K, X_e, ..."""
    if name in _ELASTICA_SYMBOLS:
        return _ELASTICA_SYMBOLS[name]
    if name == "arck":
        return r"\operatorname{K}"
    letter = {"sinr": "s", "cosr": "c"}[name[:4]]
    return rf"\operatorname{{{letter}}}_{{{name[4:]}}}"


class ReportPrinter(LatexPrinter):
    """sympy's LatexPrinter with atan2 written as one operator and symkin's special functions
    written with the report's symbols."""

    def _print_atan2(self, expr, exp=None):
        y, x = expr.args
        tex = rf"\operatorname{{atan2}}\left({self._print(y)}, {self._print(x)}\right)"
        return tex if exp is None else rf"\left({tex}\right)^{{{exp}}}"

    def _print_Function(self, expr, exp=None):
        if not special.is_special(expr):
            return super()._print_Function(expr, exp)
        symbol = special_symbol(type(expr).__name__)
        call = rf"\!\left({self._print(expr.args[0])}\right)"
        if exp is None:
            return symbol + call
        if isinstance(expr, special.ElasticaFunction):
            return rf"\left({symbol}{call}\right)^{{{exp}}}"
        return rf"{symbol}^{{{exp}}}{call}"


#: Significant digits of a constant the report shows rounded.
DISPLAY_DIGITS = 6


def display_numbers(expr: object) -> sp.Expr:
    """`expr` as the report prints it: halves, quarters, eighths, small fractions (1/840),
    surds and multiples of π exact; the file's decimal numbers as written (a CAD coordinate
    0.0851234567 stays whole, 363/200000 reads 0.001815); any other constant (250000
    sqrt(164866)/577031) rounded to DISPLAY_DIGITS significant digits."""
    return fold_numbers(sp.sympify(expr), _readable, _displayed)


def _terminating(q: sp.Rational) -> bool:
    """Its decimal expansion ends: the denominator holds no prime but 2 and 5."""
    d = q.q
    for prime in (2, 5):
        while d % prime == 0:
            d //= prime
    return d == 1


def _fraction(q: sp.Expr) -> bool:
    """A rational the report prints as a fraction."""
    if not q.is_Rational:
        return False
    if q.q in (1, 2, 4, 8):
        return True
    return not _terminating(q) and abs(q.p) <= 100 and q.q <= 10**4


def _readable(c: sp.Expr) -> bool:
    """A constant the report prints as it is: not a Float carried at more than double
    precision (a notch's 45-digit pure-moment coefficients: rounded like any other constant)."""
    if c.is_Float:
        return c._prec <= 53
    if c.is_Integer:
        return True
    if c.is_Rational:
        return _fraction(c)
    coeff, rest = c.as_coeff_Mul()
    surd = rest.is_Pow and rest.exp == sp.S.Half and rest.base.is_Integer and 0 < rest.base <= 100
    return (rest is sp.pi or surd) and _fraction(coeff)


def _displayed(c: sp.Expr) -> sp.Expr:
    """A terminating decimal exactly (at most 12 digits), anything else rounded."""
    if c.is_Rational and _terminating(c):
        text = f"{decimal.Decimal(c.p) / decimal.Decimal(c.q):f}"
        digits = len(text.replace("-", "").replace(".", "").lstrip("0"))
        if digits <= 12:
            return sp.Float(text, max(digits, 1))
    return sp.Float(sp.N(c, DISPLAY_DIGITS + 5), DISPLAY_DIGITS)


class Tex:
    """Prints sympy expressions to LaTeX with fixed symbol names, and breaks long ones. Numbers
    print as :func:`display_numbers` shows them."""

    def __init__(
        self, symbol_names: Mapping[sp.Symbol, str] | None = None, width: float = LINE_WIDTH_EM
    ) -> None:
        self.symbol_names = dict(symbol_names or {})
        self.width = width
        self.printer = self._printer()
        self._printed: dict[sp.Basic, str] = {}  # line breaking prints the same pieces often

    def _printer(self, **extra) -> ReportPrinter:
        settings = {
            "symbol_names": self.symbol_names,
            "inv_trig_style": "full",
            "fold_func_brackets": True,
            "mat_delim": "",
            "mat_str": "bmatrix",
        }
        settings.update(extra)
        return ReportPrinter(settings)

    def with_names(self, names: Mapping[sp.Symbol, str]) -> Tex:
        return Tex({**self.symbol_names, **names}, self.width)

    def __call__(self, expr: object) -> str:
        expr = sp.sympify(expr)
        tex = self._printed.get(expr)
        if tex is None:
            tex = self._printed[expr] = self.printer.doprint(display_numbers(expr))
        return tex

    def matrix(self, rows: Iterable[Iterable[object]], style: str = "bmatrix") -> str:
        """A matrix environment of the given rows (each entry printed by sympy)."""
        m = sp.Matrix([[display_numbers(e) for e in r] for r in rows])
        return self._printer(mat_str=style).doprint(m)

    def vector(self, v: Iterable[object]) -> str:
        """A column vector in parentheses."""
        return self.matrix([[e] for e in v], "pmatrix")

    def inline(self, expr: object) -> str:
        """`expr` with short fractions folded (a/b), for tables and running text."""
        return self._printer(fold_short_frac=True).doprint(display_numbers(expr))

    def table_vector(self, v: Iterable[object]) -> str:
        """A column vector for tables: a pmatrix with folded fractions."""
        body = r" \\ ".join(self.inline(e) for e in v)
        return r"\begin{pmatrix}" + body + r"\end{pmatrix}"

    def row_vector(self, v: Iterable[object]) -> str:
        """(x, y) inline, fractions folded."""
        return r"\left(" + r",\ ".join(self.inline(e) for e in v) + r"\right)"

    # -- breaking --------------------------------------------------------------------------------
    def signed_terms(self, expr: sp.Expr) -> list[tuple[str, sp.Expr]]:
        """Terms of a sum in the printer's order with their printed sign ("" for the first)."""
        terms = self.printer._as_ordered_terms(expr, order=None)
        out = []
        for i, term in enumerate(terms):
            if i == 0:
                out.append(("", term))
            elif term.could_extract_minus_sign():
                out.append(("-", -term))
            else:
                out.append(("+", term))
        return out

    def _term(self, term: sp.Expr) -> str:
        tex = self(term)
        if self.printer._needs_add_brackets(term):
            tex = rf"\left({tex}\right)"
        return tex

    def tokens(self, expr: sp.Expr, budget: float) -> list[str]:
        """Pieces whose concatenation (with spaces) prints `expr`; a line may break between any
        two. Pieces wider than `budget` are opened up where the expression allows it."""
        expr = sp.sympify(expr)
        tex = self(expr)
        if width(tex) <= budget:
            return [tex]
        if expr.is_Add:
            out: list[str] = []
            for sign, term in self.signed_terms(expr):
                head = f"{sign} " if sign else ""
                sub = self.tokens(term, budget - 1.5) if not term.is_Add else [self._term(term)]
                sub[0] = head + sub[0]
                out.extend(sub)
            return out
        if expr.is_Mul:
            return self._mul_tokens(expr, budget, tex)
        if isinstance(expr, sp.Function) and expr.args:
            return self._function_tokens(expr, budget, tex)
        if expr.is_Pow and expr.base.is_Add and expr.exp.is_Rational and expr.exp != 1:
            # (a sum)^e, a root or a reciprocal too: the sum breaks inside big parentheses
            inner = self.tokens(expr.base, budget - 3)
            return self._wrap(inner, r"\Bigl(", rf"\Bigr)^{{{self(expr.exp)}}}")
        return [tex]

    @staticmethod
    def _wrap(inner: list[str], head: str, tail: str) -> list[str]:
        inner = list(inner)
        inner[0] = head + inner[0]
        inner[-1] = inner[-1] + tail
        return inner

    def _mul_tokens(self, expr: sp.Expr, budget: float, tex: str) -> list[str]:
        coeff, rest_ = expr.as_coeff_Mul()  # any number, a decimal one too
        factors = sp.Mul.make_args(rest_)
        sign = ""
        if coeff < 0:
            sign, coeff = "- ", -coeff
        if coeff.is_Float:  # a decimal coefficient leads, as the printer puts it
            sign, coeff = sign + self(coeff) + " ", sp.Integer(1)
        num, den = sp.fraction(sp.Mul(coeff, *factors, evaluate=False))
        if den != 1:
            head = sign + self(1 / den)
            if width(head) > budget / 2:
                # a wide denominator: its factors as powers, each breaking where it must
                out = [sign.strip()] if sign else []
                for f in sp.Mul.make_args(sp.expand_power_base(den, force=True)):
                    base, exp = f.as_base_exp()
                    out += self.tokens(sp.Pow(base, -exp, evaluate=False), budget)
                return out + self._wrap(self.tokens(num, budget - 2), r"\Bigl(", r"\Bigr)")
            inner = self.tokens(num, budget - width(head) - 2)
            return self._wrap(inner, head + r" \Bigl(", r"\Bigr)")
        factors = [f for f in sp.Mul.make_args(num) if f != 1]
        if not factors:
            return [tex]
        widest = max(factors, key=lambda f: width(self(f)))
        rest = [f for f in factors if f is not widest]
        if not rest and sign == "":
            return [tex]
        # a lone sum left over keeps its parentheses (printed alone it would lose them)
        head = sign + (
            self._term(rest[0]) if len(rest) == 1 else self(sp.Mul(*rest)) if rest else ""
        )
        if head.strip() == "1":
            head = ""
        if widest.is_Add:
            inner = self.tokens(widest, budget - width(head) - 2)
            return self._wrap(inner, head + r" \Bigl(", r"\Bigr)")
        inner = self.tokens(widest, budget - width(head))
        if rest and width(head) + width(inner[0]) > budget:
            # the product itself breaks between its factors, in the printer's order
            ordered = sp.Mul(*rest).as_ordered_factors()
            pieces = [self._term(f) for f in ordered]
            pieces[0] = (sign + pieces[0]).strip()
            return pieces + inner
        inner[0] = (head + " " + inner[0]).strip()
        return inner

    def _function_tokens(self, expr: sp.Function, budget: float, tex: str) -> list[str]:
        names = {
            sp.sin: r"\sin",
            sp.cos: r"\cos",
            sp.tan: r"\tan",
            sp.atan2: r"\operatorname{atan2}",
            sp.exp: r"\exp",
            sp.atan: r"\arctan",
            sp.asin: r"\arcsin",
            sp.acos: r"\arccos",
        }
        name = names.get(expr.func)
        if name is None and isinstance(expr, sp.core.function.AppliedUndef):
            name = self.printer._deal_with_super_sub(expr.func.__name__)  # R_F, R_D
        if name is None:
            return [tex]
        out: list[str] = []
        for k, arg in enumerate(expr.args):
            sub = self.tokens(arg, budget - 2)
            if k:
                out[-1] += ","
            out.extend(sub)
        return self._wrap(out, name + r"\Bigl(", r"\Bigr)")

    def lines(
        self, expr: sp.Expr, first: float | None = None, rest: float | None = None
    ) -> list[str]:
        """`expr` packed greedily into lines: the first at most `first` ems wide, the others
        `rest` (defaults: the full width and the width less the continuation indent)."""
        first = self.width if first is None else first
        rest = self.width - 1.5 if rest is None else rest
        return pack(self.tokens(display_numbers(expr), min(first, rest)), first, rest)

    def named_equation(self, lhs: str, rhs: sp.Expr, prefix: str) -> list[str]:
        """Like :meth:`equation`, but a product too wide for one line has its sums named
        ``prefix_1, prefix_2, ...`` and defined on the following lines (OpenSYMORO style)."""
        rhs = display_numbers(rhs)
        lead = max(width(lhs), LHS_EM) + 1.5
        if width(self(rhs)) <= self.width - lead or not rhs.is_Mul:
            return self.equation(lhs, rhs)
        sums = [f for f in rhs.args if f.is_Add and width(self(f)) > 5]
        if not sums:
            return self.equation(lhs, rhs)
        symbols = [sp.Symbol(f"zz_{prefix}_{k}") for k in range(1, len(sums) + 1)]
        names = {s: rf"{prefix}_{{{k}}}" for k, s in enumerate(symbols, start=1)}
        short = rhs.xreplace(dict(zip(sums, symbols)))
        out = self.with_names(names).equation(lhs, short)
        for s, f in zip(symbols, sums):
            out += self.equation(names[s], f)
        return out

    def equation(self, lhs: str, rhs: sp.Expr, relation: str = "=") -> list[str]:
        """Lines of an ``align*`` for ``lhs = rhs``: ``lhs &= ...`` then ``&\\quad {}+ ...``."""
        # the left column of an align is as wide as its widest left side: budget for at
        # least LHS_EM so that lines with short and long left sides can share a block
        lead = max(width(lhs), LHS_EM) + 1.5
        body = self.lines(rhs, self.width - lead, self.width - lead - 1.0)
        return align_lines(lhs, relation, body)


def align_lines(lhs: str, relation: str, body: list[str]) -> list[str]:
    out = [f"{lhs} &{relation} {body[0]}"]
    for line in body[1:]:
        out.append(r"&\quad {}" + line)
    return out


def pack(tokens: list[str], first: float, rest: float) -> list[str]:
    """Greedy line filling of `tokens` (joined by spaces)."""
    lines: list[str] = []
    current, current_width = "", 0.0
    for tok in tokens:
        budget = first if not lines else rest
        tok_width = width(tok)  # widths add over a space-joined line
        if current and current_width + tok_width > budget:
            lines.append(current)
            current, current_width = tok, tok_width
        else:
            current = (current + " " + tok) if current else tok
            current_width += tok_width
    lines.append(current)
    return lines


# -- width estimate ------------------------------------------------------------------------------

_CMD_WIDTH = {
    "sin": 1.45,
    "cos": 1.55,
    "tan": 1.5,
    "exp": 1.6,
    "log": 1.4,
    "arctan": 2.9,
    "arcsin": 2.8,
    "arccos": 2.9,
    "cdot": 0.75,
    "times": 1.2,
    "quad": 1.0,
    "qquad": 2.0,
    ",": 0.17,
    "!": -0.17,
    ";": 0.28,
    ":": 0.22,
    " ": 0.33,
    "pm": 1.2,
    "mp": 1.2,
    "to": 1.5,
    "rightarrow": 1.5,
    "ldots": 1.2,
    "cdots": 1.2,
    "infty": 1.0,
    "pi": 0.6,
    "Delta": 0.85,
    "sum": 1.1,
    "leq": 1.3,
    "geq": 1.3,
    "neq": 1.3,
    "approx": 1.3,
    "equiv": 1.3,
    "circ": 0.5,
    "partial": 0.6,
    "perp": 0.8,
    "top": 0.8,
    "{": 0.5,
    "}": 0.5,
    "%": 0.8,
    "$": 0.5,
    "&": 0.8,
    "#": 0.8,
    "_": 0.5,
}
_ZERO_CMDS = {
    "left",
    "right",
    "displaystyle",
    "limits",
    "nolimits",
    "relax",
    "scriptstyle",
    "textstyle",
    "mathstrut",
    "strut",
    "protect",
}
_BIG = {"bigl", "bigr", "Bigl", "Bigr", "biggl", "biggr", "big", "Big", "bigg", "Biggl", "Biggr"}
_CHAR_WIDTH = {
    "+": 1.25,
    "-": 1.25,
    "=": 1.35,
    "<": 1.35,
    ">": 1.35,
    "(": 0.4,
    ")": 0.4,
    "[": 0.3,
    "]": 0.3,
    ",": 0.45,
    ";": 0.45,
    ".": 0.3,
    "/": 0.5,
    "|": 0.3,
    "'": 0.3,
    " ": 0.0,
    "&": 0.0,
    "~": 0.33,
}


@lru_cache(maxsize=65536)
def width(tex: str) -> float:
    """Rough width in ems of a LaTeX math string set in display style at the body font size."""
    return _Scanner(tex).group_width()


class _Scanner:
    def __init__(self, tex: str) -> None:
        self.s = tex
        self.i = 0

    def peek(self) -> str:
        return self.s[self.i] if self.i < len(self.s) else ""

    def command(self) -> str:
        j = self.i + 1
        if j < len(self.s) and self.s[j].isalpha():
            k = j
            while k < len(self.s) and self.s[k].isalpha():
                k += 1
            self.i = k
            return self.s[j:k]
        self.i = j + 1
        return self.s[j : j + 1]

    def argument(self) -> str:
        """Raw text of the next argument (a braced group or one token)."""
        while self.peek() == " ":
            self.i += 1
        if self.peek() == "{":
            depth, j = 0, self.i
            while j < len(self.s):
                if self.s[j] == "\\":
                    j += 2
                    continue
                if self.s[j] == "{":
                    depth += 1
                elif self.s[j] == "}":
                    depth -= 1
                    if depth == 0:
                        break
                j += 1
            text = self.s[self.i + 1 : j]
            self.i = j + 1
            return text
        if self.peek() == "\\":
            start = self.i
            self.command()
            return self.s[start : self.i]
        ch = self.peek()
        self.i += 1
        return ch

    def environment(self, name: str) -> float:
        end = "\\end{" + name + "}"
        j = self.s.find(end, self.i)
        body = self.s[self.i : j if j >= 0 else len(self.s)]
        self.i = (j + len(end)) if j >= 0 else len(self.s)
        if "matrix" in name or name in ("array", "aligned", "cases"):
            scale = 0.7 if name == "smallmatrix" else 1.0
            rows = [r.split("&") for r in re.split(r"\\\\", body)]
            ncol = max(len(r) for r in rows)
            cols = [max((width(r[c]) if c < len(r) else 0.0) for r in rows) for c in range(ncol)]
            return scale * (sum(cols) + 1.0 * ncol) + 0.8
        return width(body)

    def group_width(self) -> float:
        total = 0.0
        last_base = 0.0
        last_script: str | None = None
        script_width = 0.0
        while self.i < len(self.s):
            ch = self.peek()
            if ch in "^_":
                self.i += 1
                w = 0.72 * width(self.argument())
                if last_script is not None and last_script != ch:
                    # sub- and superscript stacked: only the wider counts
                    extra = max(0.0, w - script_width)
                    total += extra
                    script_width = max(script_width, w)
                else:
                    total += w
                    script_width = w
                last_script = ch
                continue
            last_script = None
            if ch == "{":
                w = width(self.argument())
            elif ch == "}":
                self.i += 1
                w = 0.0
            elif ch == "\\":
                name = self.command()
                w = self._command_width(name)
            else:
                self.i += 1
                if ch in _CHAR_WIDTH:
                    w = _CHAR_WIDTH[ch]
                elif ch.isdigit():
                    w = 0.5
                elif ch.isupper():
                    w = 0.72
                else:
                    w = 0.55
            total += w
            last_base = w
        del last_base
        return total

    def _command_width(self, name: str) -> float:
        if name in ("frac", "dfrac"):
            a, b = self.argument(), self.argument()
            return max(width(a), width(b)) + 0.3
        if name == "tfrac":
            a, b = self.argument(), self.argument()
            return 0.72 * max(width(a), width(b)) + 0.2
        if name == "sqrt":
            if self.peek() == "[":
                j = self.s.find("]", self.i)
                self.i = j + 1
            return width(self.argument()) + 1.0
        if name in ("text", "textrm", "texttt", "textit", "mathrm", "textbf", "mbox"):
            return _text_width(self.argument())
        if name in ("mathbf", "mathit", "boldsymbol", "mathsf", "mathcal", "bm"):
            return 1.1 * width(self.argument())
        if name == "operatorname":
            arg = self.argument()
            return 0.5 * len(re.sub(r"\\.|[{}]", "", arg)) + 0.3
        if name in (
            "hat",
            "bar",
            "tilde",
            "vec",
            "dot",
            "ddot",
            "check",
            "breve",
            "acute",
            "grave",
            "underline",
            "overline",
            "widehat",
            "widetilde",
        ):
            return width(self.argument())
        if name in ("hspace", "vspace", "label", "tag", "phantom", "hphantom"):
            arg = self.argument()
            return width(arg) if name in ("phantom", "hphantom") else 0.0
        if name in ("begin",):
            env = self.argument()
            return self.environment(env)
        if name == "end":
            self.argument()
            return 0.0
        if name in _ZERO_CMDS:
            if name in ("left", "right"):
                delim = self.argument()
                return 0.0 if delim == "." else 0.5
            return 0.0
        if name in _BIG:
            self.argument()
            return 0.55
        if name in _CMD_WIDTH:
            return _CMD_WIDTH[name]
        if name and name[0].isupper():
            return 0.8
        return 0.6


def _text_width(text: str) -> float:
    plain = re.sub(r"\\[a-zA-Z]+\{\}|\\[a-zA-Z]+|\\.", "x", text)
    plain = plain.replace("{", "").replace("}", "")
    return 0.5 * len(plain)
