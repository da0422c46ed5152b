"""The report's sections that restate the derivation (:class:`Report`: the template context of
one plan): the labeled graph, I, Φ, Ψ, the plate data, J and J*, the link positions (4.7), the
hinge models with their cancellation-free Δf, Δg, the loop equations (5.1)/(5.3) and their
solved forms, the closed-form rigid solution, the deviation of every point at the levels and the
loaded level's equilibrium; :mod:`.document` renders it with the figures and tables.
"""

from __future__ import annotations

import dataclasses

import sympy as sp

from ..codegen.backends.common import header_lines
from ..codegen.plan import Plan
from ..core import vectors as V
from ..physics import reduced
from .text import LINE_WIDTH_EM, Tex, align_lines, escape_latex, gnum, math_name, pack, sci, width

#: Matrices wider than this many columns are printed in column blocks (at the full width).
MAX_MATRIX_COLS = 14
#: The column the report is laid out for, in points: an article's one-column text width at
#: 10 pt; `derive --columnwidth` sets a journal's (e.g. a two-column article's 229.9 pt).
COLUMN_WIDTH = 345.0
#: The file's length unit (`units`) in the figures, the tables and the text.
PLAIN_UNITS = {"m": "m", "mm": "mm", "um": "µm"}
TEX_UNITS = {"m": r"\mathrm{m}", "mm": r"\mathrm{mm}", "um": r"\mu\mathrm{m}"}


def input_unit(mech, name: str, tex: bool = False) -> str:
    """The unit of an input: an input hinge's angle in rad, a stroke actuator's stroke in the
    file's length unit, a force actuator's force in N (docs/levels.md, "Actuators")."""
    act = next((a for a in mech.actuators if a.name == name), None)
    if act is None:
        return "rad"
    if act.drive == "force":
        return "N"
    return f"${TEX_UNITS[mech.units]}$" if tex else PLAIN_UNITS[mech.units]


def input_axis(mech, name: str, shown: str) -> str:
    """A plot's axis label for a swept input `shown` (its printable name): its angle, stroke or
    force and the unit (input_unit)."""
    act = next((a for a in mech.actuators if a.name == name), None)
    what = "input θ" if act is None else ("force" if act.drive == "force" else "stroke")
    return f"{what} of {shown} ({input_unit(mech, name)})"


UNIT_NAMES = {"m": "metres", "mm": "millimetres", "um": "micrometres"}


def float_at(expr: sp.Expr, defaults: dict) -> float:
    """`expr` at the parameters' default values (numbers), 30 digits, as a float."""
    expr = sp.sympify(expr)
    # only the parameters it reads: subs tries every pair it is given (~1000 in a large file)
    used = {s: defaults[s] for s in expr.free_symbols if s in defaults}
    return float(sp.N(expr.subs(used), 30))


def chunks(items: list, size: int) -> list[list]:
    return [items[k : k + size] for k in range(0, len(items), size)] or [[]]


def _rotation_tex(tex: Tex, angle: sp.Expr) -> str:
    r"""``\mathbf{G}(\varphi)``: the rotation matrix of the paper's (5.2)."""
    return r"\mathbf{G}\!\left(" + tex(angle) + r"\right)"


def _dz_names(m: int) -> dict[sp.Symbol, str]:
    """LaTeX names of the placeholders DZ_b of Δz_b (b = 1..m), for printing sums of them."""
    return {sp.Symbol(f"DZ_{b}"): rf"\Delta\mathbf{{z}}_{{{b}}}" for b in range(1, m + 1)}


def _dz_sum(signs) -> sp.Expr:
    """Φ_c Δz = Σ Φ_cb Δz_b over the placeholders DZ_b, from a loop's (b, Φ_cb) pairs."""
    return sp.Add(*(coeff * sp.Symbol(f"DZ_{b}") for b, coeff in signs))


class Report:
    """Builds the template context of one plan."""

    def __init__(self, plan: Plan, source: str, column_width: float = COLUMN_WIDTH) -> None:
        if plan.derivation is None:
            raise ValueError("a report needs a plan made with plan(..., report=True)")
        self.plan = plan
        self.source = source
        self.d = plan.derivation
        self.s = self.d.structure
        self.mech = self.s.mechanism
        self.defaults = dict(self.mech.defaults)
        # ems the equations are broken for: LINE_WIDTH_EM (calibrated, with a margin for the
        # estimated glyph widths) at the one-column width, in proportion elsewhere
        self.width = LINE_WIDTH_EM * column_width / COLUMN_WIDTH
        self.max_cols = max(4, int(MAX_MATRIX_COLS * self.width / LINE_WIDTH_EM))
        self.tex = Tex(self._symbol_names(), self.width)

    # -- symbols -------------------------------------------------------------------------------
    def _symbol_names(self) -> dict[sp.Symbol, str]:
        d = self.d
        names: dict[sp.Symbol, str] = {}
        for a in d.theta:
            names[d.theta[a]] = rf"\theta_{{{a}}}"
            names[d.delta[a]] = rf"\delta_{{{a}}}"
        names[d.variable] = r"\theta"
        sol = d.rigid
        for d in sol.dyads:
            h1, h2, h3 = d.hinges
            roots = (min(d.bodies[0]), min(d.bodies[1]))
            suffix = {
                "ax": rf"X_{{{h1}}}",
                "ay": rf"Y_{{{h1}}}",
                "cx": rf"X_{{{h3}}}",
                "cy": rf"Y_{{{h3}}}",
                "bx": rf"X_{{{h2}}}",
                "by": rf"Y_{{{h2}}}",
                "dsq": rf"D_{{{d.index}}}",
                "along": rf"\lambda_{{{d.index}}}",
                "reach": rf"\rho_{{{d.index}}}",
                "across": rf"\eta_{{{d.index}}}",
                "margin": rf"\mu_{{{d.index}}}",
                "phi1": rf"\varphi_{{{roots[0]}}}",
                "phi2": rf"\varphi_{{{roots[1]}}}",
            }
            for symbol, _ in sol.assignments:
                prefix = f"dyad{d.index}_"
                if symbol.name.startswith(prefix) and symbol.name[len(prefix) :] in suffix:
                    names[symbol] = suffix[symbol.name[len(prefix) :]]
        # Parameters print as sympy prints their names (l, gamma_B -> \gamma_{B}) unless the
        # name is unusual or would look like one of the report's own symbols.
        reserved = set(names.values()) | {
            r"\theta",
            r"\delta",
            "r",
            r"\beta",
            "a",
            "X",
            "Y",
            "S",
            "C",
            "D",
        }
        printer = Tex()
        for p in self.mech.parameters:
            default = printer(p.symbol)
            simple = (
                p.name[0].isalpha()
                and p.name.count("_") <= 1
                and not p.name.endswith("_")
                and p.name.replace("_", "").isalnum()
            )
            if (
                not simple
                or default in reserved
                or default.split("_")[0]
                in (
                    r"\theta",
                    r"\delta",
                    "r",
                    r"\beta",
                    "a",
                    "X",
                    "Y",
                    "D",
                    r"\varphi",
                    r"\lambda",
                    r"\rho",
                    r"\eta",
                    r"\mu",
                    "k",
                    r"\Lambda",
                    r"\chi",
                    "Q",
                )
            ):
                names[p.symbol] = r"\text{\itshape " + escape_latex(p.name) + "}"
        return names

    def link_name(self, i: int) -> str:
        return escape_latex(self.s.links[i])

    def hinge_name(self, a: int) -> str:
        return escape_latex(self.s.hinges[a - 1])

    # -- sections ------------------------------------------------------------------------------
    def context(self, appendix: bool) -> dict:
        mech, s = self.mech, self.s
        name = mech.name
        ctx = {
            "appendix": appendix,
            "header": header_lines(self.plan, self.source),
            "name": escape_latex(name),
            "label": "symkin:" + "".join(ch if ch.isalnum() else "-" for ch in name),
            "source": escape_latex(self.source),
            "figure_pose": f"{name}-pose.pdf",
            "figure_graph": f"{name}-graph.pdf",
            "n": s.n,
            "m": s.m,
            "loops": s.m - s.n,
            "mobility": mech.grubler,
            "rank_mobility": mech.mobility,
            "inputs": [escape_latex(n) for n in mech.drives],
            "actuators": [
                {
                    "name": escape_latex(a.name),
                    "hinge": escape_latex(a.surrogate),
                    "label": s.hinges.index(a.surrogate) + 1,
                }
                for a in mech.actuators
            ],
            "input_labels": list(self.d.inputs),
            "point_names": [escape_latex(p) for p in self.plan.points],
            "levels": [lv.title for lv in self.plan.levels],
            "notes": [escape_latex(n.strip()) for n in self.plan.notes],
            "four_bar": s.n == 3 and s.m == 4,
            "unit": TEX_UNITS[mech.units],
            "unit_name": UNIT_NAMES[mech.units],
            "relabeled": s.relabeled,
            "links": [
                {"label": i, "name": self.link_name(i), "ground": i == 0} for i in range(s.n + 1)
            ],
            "parameters": self.parameters(),
        }
        ctx["hinges"] = self.hinge_rows()
        ctx["matrices"] = self.structure_matrices()
        ctx["plates"] = self.plate_rows()
        ctx["alpha_equal"] = all(p["alpha_plus"] == p["alpha_minus"] for p in ctx["plates"])
        ctx["rotations"] = self.rotation_lines()
        ctx["link_deviations"] = self.link_deviation_lines()
        ctx["dz"] = self.delta_z_lines()
        ctx["jmat"] = self.j_matrices()
        ctx["positions"] = self.position_lines()
        ctx["models"], ctx["kernels"] = self.models()
        ctx["loop_eqs"] = self.loops()
        ctx["rigid"] = self.rigid_solution()
        ctx["linear"] = self.linear_system()
        ctx["points"] = self.points()
        ctx["first_order_lines"] = [ln for p in ctx["points"] for ln in p["first_order"]]
        ctx["exact_lines"] = [ln for p in ctx["points"] for ln in p["exact"]]
        ctx["matrix_cols"] = max(10, s.m, s.n + 1)
        ctx["loaded"] = self.loaded_equilibrium()
        return ctx

    def parameters(self) -> list[dict]:
        rows = []
        for p in self.mech.parameters:
            value = gnum(float_at(p.value, {}))
            expr = value if sp.sympify(p.expr).is_number else self.tex(p.expr)
            symbol = self.tex(p.symbol)
            rows.append(
                {
                    "name": escape_latex(p.name) if symbol != p.name else "",
                    "symbol": symbol,
                    "expr": expr,
                    "value": value,
                }
            )
        return rows

    def hinge_rows(self) -> list[dict]:
        s = self.s
        rows = []
        for a in range(1, s.m + 1):
            h = self.d.hinges[a]
            rows.append(
                {
                    "a": a,
                    "name": self.hinge_name(a),
                    "plus": s.i_plus[a - 1],
                    "minus": s.i_minus[a - 1],
                    "chord": a > s.n,
                    "input": h.is_input,
                    "sign": h.sign,
                }
            )
        return rows

    def _int_matrix(self, lhs: str, rows: list[list[int]], col0: int = 1) -> list[str]:
        """Display lines of an integer matrix, in column blocks when it is wide."""
        ncol = len(rows[0]) if rows else 0
        out = []
        blocks = chunks(list(range(ncol)), self.max_cols) if ncol else [[]]
        for block in blocks:
            sub_rows = [[r[c] for c in block] for r in rows]
            body = self.tex.matrix(sub_rows) if block else r"\mathbf{0}"
            if len(blocks) > 1:
                body += rf"\quad\text{{(columns {block[0] + col0}--{block[-1] + col0})}}"
            out.append(f"{lhs} = {body}")
        return out

    def structure_matrices(self) -> dict:
        s = self.s
        return {
            "I": self._int_matrix(r"\underline{I}", s.incidence.tolist()),
            "Phi": self._int_matrix(r"\underline{\Phi}", s.loops.tolist()),
            "Psi": self._int_matrix(r"\underline{\Psi}", s.paths.tolist()),
        }

    def plate_rows(self) -> list[dict]:
        s = self.s
        rows = []
        for a in range(1, s.m + 1):
            data = self.d.plates[a]
            rows.append(
                {
                    "a": a,
                    "plus": s.i_plus[a - 1],
                    "minus": s.i_minus[a - 1],
                    "c_plus": self.tex.table_vector(data["c_plus"]),
                    "c_minus": self.tex.table_vector(data["c_minus"]),
                    "alpha_plus": self.tex.inline(data["alpha_plus"]),
                    "alpha_minus": self.tex.inline(data["alpha_minus"]),
                    "length": self.tex.inline(data["length"]),
                    "model": escape_latex(self.d.hinges[a].hinge.model),
                }
            )
        return rows

    def rotation_lines(self) -> list[str]:
        """φ_i = Σ q_b over the direct path, q_b = σ_b θ_b."""
        lines = []
        for i in range(1, self.s.n + 1):
            lines += self.tex.equation(rf"\varphi_{{{i}}}", self.d.phi[i])
        return lines

    def link_deviation_lines(self) -> list[str]:
        """δφ_i = Σ σ_b δ_b over the direct path, for the links the loops turn."""
        lines = []
        for i in range(1, self.s.n + 1):
            if self.d.delta_phi[i] != 0:
                lines += self.tex.equation(rf"\delta\varphi_{{{i}}}", self.d.delta_phi[i])
        return lines

    def delta_z_lines(self) -> list[str]:
        """Δz_a = σ_a G(φ_P) (Δf_a(θ_a) u_a + Δg_a(θ_a) u_a^⊥) for every hinge."""
        tex = self.tex
        lines = []
        for a in range(1, self.s.m + 1):
            h = self.d.hinges[a]
            phi_p = self.d.phi[h.P]
            u = h.u
            first = rf"\Delta f_{{{a}}}(\theta_{{{a}}})\,{tex.table_vector(u)}"
            second = rf"\Delta g_{{{a}}}(\theta_{{{a}}})\,{tex.table_vector(V.perp(u))}"
            rot = "" if phi_p == 0 else _rotation_tex(tex, phi_p)
            sign = "-" if h.sign < 0 else ""
            open_, close = (rf"{sign}{rot}\Bigl[", r"\Bigr]") if rot or sign else ("", "")
            lhs = rf"\Delta\mathbf{{z}}_{{{a}}} &= "
            one_line = f"{lhs}{open_}{first} + {second}{close}"
            if width(one_line) <= self.width - 1:
                lines.append(one_line)
            else:  # a narrow column: the second term on a line of its own
                lines += [f"{lhs}{open_}{first}", rf"&\qquad + {second}{close}"]
        return lines

    def _abstract_names(self, exprs) -> Tex:
        """Printer naming the abstract c_{i,a}, z_{a} symbols of paper_matrices in bold."""
        names = {}
        for e in exprs:
            for symbol in sorted(sp.sympify(e).free_symbols, key=lambda x: x.name):
                if symbol.name.startswith(("c_{", "z_{")):
                    names[symbol] = r"\mathbf{" + symbol.name[0] + "}" + symbol.name[1:]
        names[sp.Symbol("O_bold")] = r"\mathbf{0}"
        return self.tex.with_names(names)

    def j_matrices(self) -> dict:
        J, Jstar = self.d.J, self.d.Jstar
        zero = sp.Symbol("O_bold")
        out = {}
        for key, lhs, M in (
            ("J", r"\underline{\mathbf{J}}", J),
            ("Jstar", r"\underline{\mathbf{J}}^{*}", Jstar),
        ):
            rows = [
                [zero if M[i, j] == 0 else M[i, j] for j in range(M.cols)] for i in range(M.rows)
            ]
            tex = self._abstract_names(list(M))
            blocks = chunks(list(range(M.cols)), max(3, self.max_cols * 10 // 14))
            lines = []
            for block in blocks:
                body = tex.matrix([[r[c] for c in block] for r in rows])
                if len(blocks) > 1:
                    body += rf"\quad\text{{(columns {block[0] + 1}--{block[-1] + 1})}}"
                lines.append(f"{lhs} = {body}")
            out[key] = lines
        return out

    def position_lines(self) -> list[str]:
        R = self.d.R
        tex = self._abstract_names(list(R))
        lines = []
        for i in range(R.rows):
            lines += tex.equation(rf"\mathbf{{R}}_{{{i + 1}}}", R[i])
        return lines

    # -- hinge models ----------------------------------------------------------------------------
    def models(self) -> tuple[list[dict], list[str]]:
        out = []
        kernels: set = set()
        for md in self.d.models:
            model = md.model
            entry = {
                "model": escape_latex(model),
                "description": escape_latex(md.description),
                "hinges": ", ".join(rf"$u_{{{a}}}$ ({self.hinge_name(a)})" for a in md.hinges),
                "lines": [],
                "param_values": [],
                "note": "",
            }
            if md.generic is not None:
                f, g, df, dg = md.generic
                tex = self.tex.with_names(
                    {
                        sp.Symbol("gamma", positive=True): r"\gamma",
                        sp.Symbol("c_theta", positive=True): r"c_{\theta}",
                    }
                )
                for key, lhs, e, prefix in (
                    ("f", r"f(\theta)", f, "F"),
                    ("g", r"g(\theta)", g, "G"),
                    ("", r"\Delta f(\theta)", df, "P"),
                    ("", r"\Delta g(\theta)", dg, "Q"),
                ):
                    lines = tex.named_equation(lhs, e, prefix)
                    if key in md.elementary:
                        lines += align_lines("", "=", tex.lines(md.elementary[key], self.width - 4))
                    entry["lines"] += lines
                for a, gamma, c in md.prbm:
                    entry["param_values"].append(
                        rf"$u_{{{a}}}$: $\gamma = {self.tex(sp.N(gamma, 6))}$, "
                        rf"$c_{{\theta}} = {self.tex(sp.N(c, 6))}$"
                    )
                if model == "elastica_force":
                    entry["lines"] += _elastica_lines(self.tex, self.d.variable)
                    entry["note"] = (
                        "$X_e$, $Y_e$ are the coordinates over $l$ of the tip of a "
                        "cantilever bent by a transverse end force (Bisshopp--Drucker), "
                        "in Carlson's symmetric elliptic integrals $R_F$, $R_D$; they "
                        "exist for $|\\theta| < \\pi/2$. The differences "
                        "$\\Delta X_e = X_e - \\cos^2\\frac{\\theta}{2}$ and "
                        "$\\Delta Y_e = Y_e - \\frac{1}{2}\\sin\\theta$ are "
                        "evaluated as written, without cancellation."
                    )
            else:
                # table / expr: the hinge's own functions (numbers rounded for print)
                for a in md.hinges:
                    h = self.d.hinges[a]
                    for lhs, e in (
                        (rf"f_{{{a}}}(\theta)", h.f),
                        (rf"g_{{{a}}}(\theta)", h.g),
                        (rf"\Delta f_{{{a}}}(\theta)", h.df),
                        (rf"\Delta g_{{{a}}}(\theta)", h.dg),
                    ):
                        e = _rounded(e) if model == "table" else _as_written(e)
                        entry["lines"] += self.tex.equation(lhs, e)
                if model == "expr":
                    entry["note"] = (
                        "The deviation of an \\texttt{expr} model is the plain "
                        "difference from the ideal revolute (not cancellation-free). "
                        "An expression that is $0/0$ at $\\theta = 0$ is evaluated below "
                        "$|\\theta| = 10^{-3}$ by its Taylor polynomial of degree 8."
                    )
            kernels.update(md.kernels)
            out.append(entry)
        kernel_lines = []
        x = sp.Symbol("x")
        for cls in sorted(kernels, key=lambda c: c.__name__):
            series = sp.Add(*(cls.coeff(k) * x ** (2 * k) for k in range(3))) + sp.O(x**6)
            lhs = self.tex(cls(x))
            kernel_lines.append(f"{lhs} &= {self.tex(cls.elementary(x))} = {self.tex(series)}")
        return out, kernel_lines

    # -- loops -----------------------------------------------------------------------------------
    def loops(self) -> list[dict]:
        s, tex = self.s, self.tex
        out = []
        dz_tex = tex.with_names(_dz_names(s.m))
        for lp in self.d.loops:
            eq, c, hinges = lp.equations, lp.chord, lp.hinges
            r = {t.link: sp.Symbol(f"r_{t.link}", positive=True) for t in eq.terms}
            beta = {t.link: sp.Symbol(f"beta_{t.link}", real=True) for t in eq.terms}
            names = {r[i]: rf"r_{{{i}}}" for i in r}
            names.update({beta[i]: rf"\beta_{{{i}}}" for i in beta})
            ltex = tex.with_names(names)
            sym = dataclasses.replace(
                eq, terms=tuple(t._replace(r=r[t.link], beta=beta[t.link]) for t in eq.terms)
            )
            x = sp.Add(*(t.r * sp.cos(p + t.beta) for t, p in zip(sym.terms, sym.phi)))
            y = sp.Add(*(t.r * sp.sin(p + t.beta) for t, p in zip(sym.terms, sym.phi)))
            psi = {t.link: sp.Symbol(f"psi_{t.link}", real=True) for t in eq.terms}
            ptex = ltex.with_names({psi[i]: rf"\psi_{{{i}}}" for i in psi})
            angular = tex.equation("0", eq.angular)
            angular[-1] += r" \tag*{(5.1)}"
            compliant = dz_tex.equation(r"\mathbf{0}", _dz_sum(lp.signs))
            compliant[-1] += r" \tag*{(5.3)}"
            entry = {
                "chord": c,
                "name": self.hinge_name(c),
                "hinges": ", ".join(rf"$u_{{{b}}}$" for b in hinges),
                "links": ", ".join(rf"$s_{{{i}}}$" for i in lp.links),
                "constraints": angular + compliant,
                "terms": [],
                "x": ltex.equation("0", x),
                "y": ltex.equation("0", y),
                "squared": [],
                "solved": [],
                "eliminated": eq.eliminated,
            }
            weights = lp.weights
            phis = dict(zip(eq.links, eq.phi))
            for t in eq.terms:
                entry["terms"].append(
                    {
                        "link": t.link,
                        "vec": tex.table_vector(weights[t.link]),
                        "r": tex.inline(t.r),
                        "beta": tex.inline(t.beta),
                        "r_num": sci(float_at(t.r, self.defaults), 6),
                        "beta_num": f"{float_at(t.beta, self.defaults):.6f}",
                        "phi": tex(phis[t.link]),
                    }
                )
            if eq.eliminated is not None:
                j = eq.eliminated
                # the same loop over ψ_i = φ_i + β_i: r_j² - Σ r_i² = 2 Σ r_i r_k cos(ψ_i - ψ_k)
                polar = dataclasses.replace(
                    eq,
                    terms=tuple(t._replace(r=r[t.link], beta=psi[t.link]) for t in eq.terms),
                    phi=tuple(sp.Integer(0) for _ in eq.terms),
                )
                elim = polar.eliminating(j)
                entry["squared"] = _relation_lines(ptex, elim.squared.lhs, elim.squared.rhs)
                others = [t for t in polar.terms if t.link != j]
                S = sp.Add(*(t.r * sp.sin(t.beta) for t in others))
                C = sp.Add(*(t.r * sp.cos(t.beta) for t in others))
                S_sym, C_sym = sp.Symbol("S_elim"), sp.Symbol("C_elim")
                stex = ptex.with_names({S_sym: rf"S_{{{j}}}", C_sym: rf"C_{{{j}}}"})
                entry["solved"] = (
                    stex.equation(rf"S_{{{j}}}", S)
                    + stex.equation(rf"C_{{{j}}}", C)
                    + [
                        rf"\psi_{{{j}}} &= {stex(sp.atan2(-S_sym, -C_sym))}",
                        rf"\varphi_{{{j}}} &= \psi_{{{j}}} - \beta_{{{j}}}",
                    ]
                )
            out.append(entry)
        return out

    # -- rigid solution --------------------------------------------------------------------------
    def rigid_solution(self) -> dict:
        sol, tex = self.d.rigid, self.tex
        dyads = []
        for d in sol.dyads:
            h1, h2, h3 = d.hinges
            dyads.append(
                {
                    "k": d.index,
                    "hinges": [(a, self.hinge_name(a)) for a in d.hinges],
                    "bodies": [", ".join(f"$s_{{{i}}}$" for i in body) for body in d.bodies],
                    "chord": d.chord,
                    "chord_name": self.hinge_name(d.chord),
                    "branch": "+1" if d.branch > 0 else "-1",
                    "h1": h1,
                    "h2": h2,
                    "h3": h3,
                    "roots": (min(d.bodies[0]), min(d.bodies[1])),
                }
            )
        steps = []
        for symbol, expr in sol.assignments:
            steps += tex.equation(tex(symbol), expr)
        phi = []
        thetas = []
        if sol.closed_form:
            for i in range(1, self.s.n + 1):
                e = sol.phi[i]
                if tex(e) != rf"\varphi_{{{i}}}":
                    phi += tex.equation(rf"\varphi_{{{i}}}", e)
            varphi = {
                i: sp.Symbol(f"varphi_{i}") if i else sp.Integer(0) for i in range(self.s.n + 1)
            }
            vtex = tex.with_names({v: rf"\varphi_{{{i}}}" for i, v in varphi.items() if i})
            for a in self.d.unknowns:
                h = self.d.hinges[a]
                thetas.append(rf"\theta_{{{a}}} &= {vtex(varphi[h.M] - varphi[h.P])}")
        return {
            "closed_form": sol.closed_form,
            "dyads": dyads,
            "steps": steps,
            "phi": phi,
            "thetas": thetas,
        }

    # -- first order ---------------------------------------------------------------------------
    def linear_system(self) -> dict | None:
        if self.d.linear is None:
            return None
        A, _ = self.d.linear
        entries = []
        named = []
        for i in range(A.rows):
            row = []
            for k in range(A.cols):
                e = A[i, k]
                if e.is_number:
                    row.append(e)
                else:
                    symbol = sp.Symbol(f"A_{i + 1}_{k + 1}")
                    row.append(symbol)
                    named.append((i + 1, k + 1, symbol, e))
            entries.append(row)
        names = {sym: rf"a_{{{i},{k}}}" for i, k, sym, _ in named}
        atex = self.tex.with_names(names)
        matrix = atex.matrix(entries)
        defs = []
        for i, k, _sym, e in named:
            defs += self.tex.equation(rf"a_{{{i},{k}}}", e)
        dz_tex = self.tex.with_names(_dz_names(self.s.m))
        rows_r = [{"chord": lp.chord, "sum": dz_tex(_dz_sum(lp.signs))} for lp in self.d.loops]
        delta = r"\left(" + ", ".join(self.tex(d) for d in self.d.deltas) + r"\right)^{T}"
        return {
            "matrix": matrix,
            "defs": defs,
            "rows": rows_r,
            "delta": delta,
            "size": len(self.d.deltas),
            "nrows": A.rows,
        }

    # -- points ----------------------------------------------------------------------------------
    def points(self) -> list[dict]:
        tex = self.tex
        out = []
        for pt in self.d.points:
            name, k, path = pt.name, pt.link, pt.path
            sub_name = math_name(name)
            entry = {
                "name": escape_latex(name),
                "link": k,
                "link_name": self.link_name(k),
                "at": tex.row_vector(pt.at),
                "path": path,
                "moved": pt.moved,
                "levels": {},
            }
            rigid = pt.rigid
            entry["rigid"] = tex.equation(rf"X_{{{sub_name}}}", rigid[0]) + tex.equation(
                rf"Y_{{{sub_name}}}", rigid[1]
            )
            dz_sum = " + ".join(rf"\Delta\mathbf{{z}}_{{{b}}}" for b in path) or r"\mathbf{0}"
            entry["paper_sum"] = (
                rf"\Delta\mathbf{{R}}_{{{sub_name}}}^{{\mathrm{{paper}}}} = "
                rf"{dz_sum}"
            )
            # multiplied out (trigonometric functions kept): one term per hinge and kernel
            dev = [sp.expand(e) for e in pt.paper]
            entry["paper"] = tex.equation(
                rf"\Delta X_{{{sub_name}}}^{{\mathrm{{paper}}}}", dev[0]
            ) + tex.equation(rf"\Delta Y_{{{sub_name}}}^{{\mathrm{{paper}}}}", dev[1])
            terms_lin, terms_exact = [], []
            for _i, w, dphi, phi in pt.turns:
                rot = "" if phi == 0 else _rotation_tex(tex, phi)
                factor = tex(dphi)
                if dphi.is_Add:
                    factor = r"\left(" + factor + r"\right)"
                terms_lin.append(rf"{factor}\,{rot}{tex.table_vector(V.perp(w))}")
                terms_exact.append(
                    rf"{rot}\Bigl(\mathbf{{G}}\!\left({tex(dphi)}\right) - "
                    rf"\mathbf{{E}}\Bigr){tex.table_vector(w)}"
                )
            lhs1 = rf"\Delta\mathbf{{R}}_{{{sub_name}}}^{{(1)}}"
            base = rf"\Delta\mathbf{{R}}_{{{sub_name}}}^{{\mathrm{{paper}}}}"
            toks = [base] + [f"+ {t}" for t in terms_lin]
            lead = width(lhs1) + 1.5
            entry["first_order"] = align_lines(
                lhs1, "=", pack(toks, self.width - lead, self.width - lead - 1)
            )
            lhs2 = rf"\Delta\mathbf{{R}}_{{{sub_name}}}"
            dzc = [
                rf"\Delta\mathbf{{z}}_{{{b}}}(\theta_{{{b}}}"
                + (rf" + \delta_{{{b}}}" if b in self.d.unknowns else "")
                + ")"
                for b in path
            ] or [r"\mathbf{0}"]
            terms = terms_exact + dzc
            toks = terms[:1] + [f"+ {t}" for t in terms[1:]]
            entry["exact"] = align_lines(
                lhs2, "=", pack(toks, self.width - lead, self.width - lead - 1)
            )
            out.append(entry)
        return out

    # -- the loaded level ------------------------------------------------------------------------
    def loaded_equilibrium(self) -> dict | None:
        """The `loaded` level's statement (docs/physics.md, "`loaded`: Newton on the reduced
        equilibrium"): the plates' stiffness, the loads, the unknowns and rows, every hinge's
        force in the chord loads and every plate's mid-frame, the solver's thresholds."""
        ld = self.d.loaded
        if ld is None or self.mech.actuators:
            # the statement has no actuators yet (their surrogates free, a stroke's force and
            # row, a force's load: docs/physics.md, "Actuators at loaded")
            return None
        mech, tex = self.mech, self.tex
        unit = TEX_UNITS[mech.units]
        names = {}
        for c, (nx, ny, mu) in ld.chord_loads.items():
            names.update({nx: rf"n_{{{c},x}}", ny: rf"n_{{{c},y}}", mu: rf"\mu_{{{c}}}"})
        ltex = tex.with_names(names)
        plates = []
        for a, stiff in ld.plates:
            sec = stiff.section
            EI, length = stiff.EI, stiff.length
            stretch = (EI / (stiff.EA * length**2), EI / (stiff.kGA * length**2))
            plates.append(
                {
                    "a": a,
                    "name": self.hinge_name(a),
                    "length": sci(float_at(length, self.defaults)),
                    "thickness": sci(float_at(sec.thickness, self.defaults)),
                    "width": sci(float_at(sec.width, self.defaults)),
                    "modulus": sci(float_at(sec.modulus(), self.defaults)),
                    "EI": sci(float_at(EI, self.defaults)),
                    "k": sci(float_at(EI / length, self.defaults)),
                    # the relation's stretch and shear compliances: none in the elastica
                    "stretch": [
                        sci(float_at(e, self.defaults)) if stiff.stretches else "0" for e in stretch
                    ],
                }
            )
        loads = [
            {
                "index": load.index + 1,
                "point": escape_latex(load.point) if load.point else "--",
                "link": self.link_name(self.s.links.index(load.link)),
                "at": tex.row_vector(load.at),
                "force": tex.row_vector(load.force),
                "moment": tex.inline(load.moment),
            }
            for load in ld.loads
        ]
        frames = dict(ld.frames)
        pairs = [
            (rf"\mathbf{{n}}_{{{a}}} &= {ltex.table_vector(n)}", a, frames.get(a))
            for a, n in ld.forces
        ]
        # side by side when every pair fits (align* shares its columns between the rows), else
        # each frame on lines of its own; a pin has no plate, so no frame
        fits = all(
            beta is None or width(f) + width(tex(beta)) + 5 <= self.width for f, _, beta in pairs
        )
        forces = []
        for f, a, beta in pairs:
            if beta is None:
                forces.append(f)
            elif fits:
                forces.append(rf"{f}, & \beta_{{{a}}} &= {tex(beta)}")
            else:
                forces += [f + ","] + tex.equation(rf"\beta_{{{a}}}", beta)
        unknowns = [tex(self.d.delta[a]) for a in self.d.unknowns]
        for c in ld.chord_loads:
            unknowns += [rf"\mathbf{{n}}_{{{c}}}", rf"\mu_{{{c}}}"]
        return {
            "plates": plates,
            "loads": loads,
            "forces": forces,
            "unknowns": ", ".join(f"${u}$" for u in unknowns),  # each breakable from the next
            "chords": [str(c) for c in ld.chord_loads],
            "balanced": [str(a) for a in ld.balanced],
            "related": [str(c) for c in ld.related],
            "offset": ld.offset,
            "unit": unit,
            "max_turn": gnum(reduced.RULES.max_turn),
            "p_limit": gnum(round(100 * reduced.RULES.p_limit)),
            "est_factor": gnum(reduced.RULES.est_factor),
            "est_limit": gnum(round(100 * reduced.RULES.est_limit)),
        }


def _elastica_lines(tex: Tex, t: sp.Symbol) -> list[str]:
    """The tip-force elastica's functions of the tip angle `t` in Carlson form (as
    symkin.special.elastica evaluates them)."""
    A, C = sp.Symbol("A"), sp.Symbol("C")
    RF, RD = sp.Function("R_F"), sp.Function("R_D")
    s = sp.Abs(sp.sin(t))
    args = (1 - s, 1 + s, sp.cos(t) ** 2)
    lines = []
    for lhs, rhs in (
        (r"X_e(\theta)", 1 / A),
        (r"Y_e(\theta)", sp.sin(t) * (1 - C / A)),
        (
            r"\Delta X_e(\theta)",
            sp.Mul(
                sp.sin(t) ** 2,
                sp.Add(1 / (2 * (1 + sp.cos(t))), -(A - 1) / (sp.sin(t) ** 2 * A), evaluate=False),
                evaluate=False,
            ),
        ),
        (r"\Delta Y_e(\theta)", sp.sin(t) * (sp.Rational(1, 2) - C / A)),
        ("A", RF(*args)),
        ("C", sp.cos(t) ** 2 / 3 * RD(*args)),
    ):
        lines += tex.equation(lhs, rhs)
    return lines


def _rounded(expr: sp.Expr) -> sp.Expr:
    """Rationals of a fitted table model shown as 6-digit floats."""
    return sp.sympify(expr).xreplace(
        {q: sp.Float(q, 6) for q in sp.sympify(expr).atoms(sp.Rational) if q.q > 1000}
    )


def _relation_lines(tex: Tex, lhs: sp.Expr, rhs: sp.Expr) -> list[str]:
    """``lhs = rhs`` with both sides possibly long: lhs lines, then ``&= rhs`` lines."""
    left = tex.lines(lhs, tex.width - 4, tex.width - 4)
    right = tex.lines(rhs, tex.width - 4, tex.width - 5)
    if len(left) == 1 and width(left[0]) + width(right[0]) < tex.width - 3 and len(right) == 1:
        return [f"{left[0]} &= {right[0]}"]
    out = [f"&{left[0]}"] + [r"&\quad {}" + ln for ln in left[1:]]
    out.append(f"&= {right[0]}")
    out += [r"&\quad {}" + ln for ln in right[1:]]
    return out


def _as_written(e: sp.Expr) -> sp.Expr:
    """An `expr` model's function as the file writes it: a removable singularity's Taylor
    branch (model.hinges.removable_at_zero) left out of print, as the report's note says."""
    return e.replace(lambda x: isinstance(x, sp.Piecewise), lambda x: x.args[-1].expr)
