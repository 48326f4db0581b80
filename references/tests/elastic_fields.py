"""Exact elastic fields for the elastic references' tests (scene-grammar strings, docs/elasticity.md),
each checked in test_dolfinx_elastic.py against Hooke's law and equilibrium by sdexpr's symbolic
derivatives:

    patch(m)                 a uniform compression σ = (0, −1, 0): u linear
    williams(m, k1, k2)      Williams' tip fields of mode I and II at the origin, the crack behind
                             it along the negative x axis (θ = atan2(y, x) = ±π on its faces)
    closed_slip(m, c, k2)    u_C = c (0.3 sin x cos y, −sin y (2 + cos x)) + mode II: closed on
                             y = 0, x < 0 (σ_yy < 0, [u_y] = 0), sliding; f = −div σ(u_C)

`m`: elastic_export.material()'s dict (λ* = lambda_in_plane, μ, κ = kolosov). Standard library only.
"""

def num(v):
    """A float as exact scene text."""
    return f"({float(v)!r})"


def patch(m, sxx=0.0, shift=(0.0, 0.0)):
    """u with the uniform stress σ = (sxx, −1, 0) (in-plane law: tr ε = (σ_xx + σ_yy)/(2(λ* + μ)),
    ε_ii = (σ_ii − λ* tr ε)/(2μ)), u = (ε_xx (x + shift_x), ε_yy (y + shift_y)): σ_xy = 0 on any
    crack along y = 0, which a frictionless crack transmits exactly."""
    lam, mu = m["lambda_in_plane"], m["mu"]
    tr = (sxx - 1.0) / (2 * (lam + mu))
    exx, eyy = (sxx - lam * tr) / (2 * mu), (-1.0 - lam * tr) / (2 * mu)
    return {"ux": f"{num(exx)}*(x + {num(shift[0])})", "uy": f"{num(eyy)}*(y + {num(shift[1])})",
            "sxx": num(sxx), "syy": "-1", "sxy": "0"}


R = "sqrt(x^2 + y^2)"
T = "atan2(y, x)"


def williams(m, k1=1.0, k2=0.0):
    """Mode I (K_I = k1) + mode II (K_II = k2) at the origin, crack along x < 0 (tip frame e₁ = x)."""
    kappa, mu = m["kolosov"], m["mu"]
    amp = f"sqrt({R}/(2*pi))/(2*{num(mu)})"
    c, s, c3, s3 = (f"{f}({k}*{T}/2)" for f, k in (("cos", 1), ("sin", 1), ("cos", 3), ("sin", 3)))
    ct = f"cos({T})"
    ux = (f"{num(k1)}*{amp}*{c}*({num(kappa)} - {ct})"
          f" + {num(k2)}*{amp}*{s}*({num(kappa)} + 2 + {ct})")
    uy = (f"{num(k1)}*{amp}*{s}*({num(kappa)} - {ct})"
          f" - {num(k2)}*{amp}*{c}*({num(kappa)} - 2 + {ct})")
    sc = f"1/sqrt(2*pi*{R})"
    sxx = f"{sc}*({num(k1)}*{c}*(1 - {s}*{s3}) - {num(k2)}*{s}*(2 + {c}*{c3}))"
    syy = f"{sc}*({num(k1)}*{c}*(1 + {s}*{s3}) + {num(k2)}*{s}*{c}*{c3})"
    sxy = f"{sc}*({num(k1)}*{c}*{s}*{c3} + {num(k2)}*{c}*(1 - {s}*{s3}))"
    opening = f"{num(k1 * (kappa + 1) / mu)}*sqrt(-x/(2*pi))"
    slip = f"{num(k2 * (kappa + 1) / mu)}*sqrt(-x/(2*pi))"
    return {"ux": ux, "uy": uy, "sxx": sxx, "syy": syy, "sxy": sxy, "opening": opening, "slip": slip}


def closed_slip(m, c=0.1, k2=1.0):
    """u_C + mode II (module documentation): (exact dict, f [fx, fy])."""
    lam, mu = m["lambda_in_plane"], m["mu"]
    a, b = 0.3 * c, c
    ux_c, uy_c = f"{num(a)}*sin(x)*cos(y)", f"-{num(b)}*sin(y)*(2 + cos(x))"
    # ε(u_C): ∂x u_x = a cos x cos y, ∂y u_y = −b cos y (2 + cos x), 2ε_xy = (b − a) sin x sin y
    tr = f"({num(a)}*cos(x)*cos(y) - {num(b)}*cos(y)*(2 + cos(x)))"
    sxx_c = f"{num(lam)}*{tr} + {num(2 * mu * a)}*cos(x)*cos(y)"
    syy_c = f"{num(lam)}*{tr} - {num(2 * mu * b)}*cos(y)*(2 + cos(x))"
    sxy_c = f"{num(mu * (b - a))}*sin(x)*sin(y)"
    # −div σ(u_C)
    fx = f"-sin(x)*cos(y)*{num(lam * (b - a) - 2 * mu * a + mu * (b - a))}"
    fy = f"-sin(y)*({num(mu * (b - a) - lam * a)}*cos(x) + {num((lam + 2 * mu) * b)}*(2 + cos(x)))"
    w = williams(m, 0.0, k2)
    exact = {"ux": f"{ux_c} + {w['ux']}", "uy": f"{uy_c} + {w['uy']}", "sxx": f"{sxx_c} + {w['sxx']}",
             "syy": f"{syy_c} + {w['syy']}", "sxy": f"{sxy_c} + {w['sxy']}", "opening": "0", "slip": w["slip"]}
    return exact, [fx, fy]


def stress_of(m, ux, uy):
    """The in-plane Hooke law of u's symbolic derivatives (sdexpr), as numpy functions (x, y) ->
    (σ_xx, σ_yy, σ_xy): what the tests compare the written stresses with."""
    from sdshared import sdexpr

    d = {(c, v): sdexpr.to_numpy(sdexpr.derivative(s, v)) for c, s in (("x", ux), ("y", uy)) for v in ("x", "y")}
    lam, mu = m["lambda_in_plane"], m["mu"]

    def sigma(x, y):
        exx, eyy = d["x", "x"](x, y), d["y", "y"](x, y)
        exy = (d["x", "y"](x, y) + d["y", "x"](x, y)) / 2
        return lam * (exx + eyy) + 2 * mu * exx, lam * (exx + eyy) + 2 * mu * eyy, 2 * mu * exy

    return sigma


def divergence_of(sxx, syy, sxy):
    """div σ of stress strings by sdexpr's symbolic derivatives, as a numpy function (x, y) -> (2,)."""
    from sdshared import sdexpr

    dx = {k: sdexpr.to_numpy(sdexpr.derivative(s, "x")) for k, s in (("xx", sxx), ("xy", sxy))}
    dy = {k: sdexpr.to_numpy(sdexpr.derivative(s, "y")) for k, s in (("xy", sxy), ("yy", syy))}
    return lambda x, y: (dx["xx"](x, y) + dy["xy"](x, y), dx["xy"](x, y) + dy["yy"](x, y))


GETFEM_DOMAIN = ((0.0, -0.5), (1.0, 0.5))
GETFEM_CRACK = ((0.0, 0.0), (0.5, 0.0))


def getfem_scene():
    """GetFEM's crack demo as a traction / fixed-point scene: [0, 1] × [−½, ½], the edge crack y = 0,
    x ≤ ½ from the left side, μ = λ = 1 (plane strain), t = 0.4 sin(2πy) n on x = 0 and x = 1 (n the
    outward normal), zero traction on top and bottom, f = (0, 3.5 cos(2πx) y x (1 − x)), u(1, −½) = 0,
    u_x(1, ½) = 0. Returns the keyword arguments of elastic_export but the material."""
    return {"f": ["0", "3.5*cos(2*pi*x)*y*x*(1 - x)"],
            "tractions": {"left": ["-0.4*sin(2*pi*y)", "0"], "right": ["0.4*sin(2*pi*y)", "0"],
                          "bottom": ["0", "0"], "top": ["0", "0"]},
            "fixed": [{"point": [1.0, -0.5], "components": ["x", "y"]}, {"point": [1.0, 0.5], "components": ["x"]}],
            "domain": GETFEM_DOMAIN, "crack": GETFEM_CRACK}

