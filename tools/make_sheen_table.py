#!/usr/bin/env python3
"""Writes src/materials/sheen_table.rs: the directional albedos of
KHR_materials_sheen's BRDF that its albedo-scaling layering looks up,

    sheen_albedo_scaling = min(1 − max3(C) E(n·v, ρ), 1 − max3(C) E(n·l, ρ))

    python3 tools/make_sheen_table.py [--nodes N] [--check]

Two tables, with a white sheen colour:

* `E_CHARLIE(μo, ρ) = ∫ f_charlie(ωo, ωi) cos θi dωi`, the albedo of the
  BRDF the specification's implementation notes give: the "Charlie"
  distribution and visibility of Conty & Kulla 2017, f_charlie = D G /
  (4 μo μi), D = (2 + 1/α)(1 − h_z²)^(1/(2α)) / (2π), G = 1 / (1 + Λ(μo) +
  Λ(μi)) with Λ the specification's fit, α = max(ρ², ALPHA_MIN) (the
  specification's `alpha_g = sheenRoughness²`; ALPHA_MIN keeps 1/α finite at
  ρ = 0). That fit's Λ is too small near the horizon for a narrow lobe:
  E_CHARLIE exceeds 1 at grazing angles below ρ ≈ 0.3 (1.75 at μo = 1/64,
  ρ = 0.1), so that sheen alone would reflect more light than it receives.
* `E(μo, ρ)`, the albedo of the BRDF raylab uses, f_charlie / max(1,
  Ê(μo), Ê(μi)) with Ê the bilinear lookup of E_CHARLIE: the specification's
  BRDF wherever its albedo is at most 1 both ways, reciprocal, and never
  reflecting more than it receives; this is the E of the albedo scaling.

The integral runs over μi = t² (nodes crowd the horizon, where a narrow
sheen lobe lives) and φ ∈ [0, π] (the lobe is symmetric about the plane of
incidence), each with Gauss–Legendre nodes; `--check` also integrates with
more nodes and prints the largest difference. The table's rows are ρ = j/31,
its columns μo = (i + ½)/32 (cell centres, so that μo = 0, where the BRDF is
singular, is never evaluated); raylab interpolates bilinearly, linearly
extended over the half cells at the edges of μo. Pure Python, no dependencies: about a minute.
"""

import argparse
import math
import os
import sys

SIZE = 32
ALPHA_MIN = 1e-3


def gauss_legendre(n):
    """Nodes and weights of the n-point Gauss–Legendre rule on [0, 1]."""
    nodes, weights = [], []
    for k in range(1, n + 1):
        x = math.cos(math.pi * (k - 0.25) / (n + 0.5))
        for _ in range(100):
            p0, p1 = 1.0, x
            for j in range(2, n + 1):
                p0, p1 = p1, ((2 * j - 1) * x * p1 - (j - 1) * p0) / j
            dp = n * (x * p1 - p0) / (x * x - 1.0)
            step = p1 / dp
            x -= step
            if abs(step) < 1e-15:
                break
        nodes.append(0.5 * (1.0 - x))
        weights.append(1.0 / ((1.0 - x * x) * dp * dp))
    return nodes, weights


def mix(a, b, t):
    return a + (b - a) * t


def l_fit(x, alpha):
    """The specification's `l(x, alpha_g)`."""
    t = (1.0 - alpha) * (1.0 - alpha)
    a = mix(21.5473, 25.3245, t)
    b = mix(3.82987, 3.32435, t)
    c = mix(0.19823, 0.16801, t)
    d = mix(-1.97760, -1.27393, t)
    e = mix(-4.32054, -4.85967, t)
    return a / (1.0 + b * x**c) + d * x + e


def lambda_sheen(cos, alpha):
    """The specification's `lambda_sheen(cos_theta, alpha_g)`."""
    if abs(cos) < 0.5:
        return math.exp(l_fit(cos, alpha))
    return math.exp(2.0 * l_fit(0.5, alpha) - l_fit(1.0 - cos, alpha))


def lookup(row, mu):
    """The lookup of raylab's `sheen::lookup` along one row (ρ a node):
    linear between the cell centres (i + ½)/SIZE, extended linearly over the
    half cells at μ = 0 and μ = 1."""
    x = min(max(mu * SIZE - 0.5, -0.5), SIZE - 0.5)
    i = min(max(int(math.floor(x)), 0), SIZE - 2)
    t = x - i
    return row[i] * (1.0 - t) + row[i + 1] * t


def albedo(mu_o, rho, t_rule, phi_rule, charlie_row=None):
    """E_CHARLIE(μo, ρ) by the product rule `t_rule` (μi = t²) ×
    `phi_rule`; with `charlie_row` (E_CHARLIE's row at ρ), E(μo, ρ)."""
    alpha = max(rho * rho, ALPHA_MIN)
    inv_r = 1.0 / alpha
    norm = (2.0 + inv_r) / (2.0 * math.pi)
    sin_o = math.sqrt(max(0.0, 1.0 - mu_o * mu_o))
    lam_o = lambda_sheen(mu_o, alpha)
    total = 0.0
    for t, wt in zip(*t_rule):
        mu_i = t * t
        sin_i = math.sqrt(max(0.0, 1.0 - mu_i * mu_i))
        g = 1.0 / (1.0 + lam_o + lambda_sheen(mu_i, alpha))
        if charlie_row is not None:
            g /= max(1.0, lookup(charlie_row, mu_o), lookup(charlie_row, mu_i))
        inner = 0.0
        for u, wu in zip(*phi_rule):
            phi = math.pi * u
            hx = sin_o + sin_i * math.cos(phi)
            hy = sin_i * math.sin(phi)
            hz = mu_o + mu_i
            cos2h = hz * hz / (hx * hx + hy * hy + hz * hz)
            inner += wu * norm * (1.0 - cos2h) ** (0.5 * inv_r)
        # dω = dμi dφ, μi = t²: dμi = 2t dt; φ over [0, π] counted twice.
        total += wt * 2.0 * t * g / (4.0 * mu_o) * inner * 2.0 * math.pi
    return total


def tables(nodes):
    """(E_CHARLIE, E), each a list of rows."""
    t_rule = gauss_legendre(nodes)
    phi_rule = gauss_legendre(nodes)
    charlie, used = [], []
    for j in range(SIZE):
        rho = j / (SIZE - 1)
        mus = [(i + 0.5) / SIZE for i in range(SIZE)]
        row = [albedo(mu, rho, t_rule, phi_rule) for mu in mus]
        charlie.append(row)
        used.append([albedo(mu, rho, t_rule, phi_rule, row) for mu in mus])
    return charlie, used


def rust_table(name, doc, rows):
    lines = [f"/// {doc}", "#[rustfmt::skip]", f"pub static {name}: [[f32; SIZE]; SIZE] = ["]
    for row in rows:
        # (Values below f32's normal range are written as 0.)
        lines.append("    [" + ", ".join(f"{v:.6e}" if v >= 1e-30 else "0.0" for v in row) + "],")
    lines.append("];")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--nodes", type=int, default=96, help="Gauss–Legendre nodes per axis")
    parser.add_argument("--check", action="store_true", help="also integrate with 1.5× the nodes")
    parser.add_argument(
        "-o",
        default=os.path.join(os.path.dirname(__file__), "..", "src", "materials", "sheen_table.rs"),
        help="the Rust file written",
    )
    args = parser.parse_args()
    charlie, used = tables(args.nodes)
    if args.check:
        finer = tables(args.nodes * 3 // 2)
        for name, a, b in (("E_CHARLIE", charlie, finer[0]), ("E", used, finer[1])):
            worst = max(abs(x - y) for r, s in zip(a, b) for x, y in zip(r, s))
            print(f"{name}: largest change with {args.nodes * 3 // 2} nodes: {worst:.2e}", file=sys.stderr)
    lines = [
        "//! Generated by `python3 tools/make_sheen_table.py`; do not edit.",
        "//!",
        "//! Directional albedos of `KHR_materials_sheen`'s BRDF (white, by",
        f"//! {args.nodes}² Gauss–Legendre nodes): row `j` is ρ = j/{SIZE - 1}, column `i`",
        f"//! is cos θo = (i + ½)/{SIZE}. See the tool for their definitions.",
        "",
        "// Seven significant digits, written as computed in f64.",
        "#![allow(clippy::excessive_precision)]",
        "",
        "/// The tables' size in each direction.",
        f"pub const SIZE: usize = {SIZE};",
        "",
        "/// The smallest `α = ρ²` the tables (and the BRDF) use.",
        f"pub const ALPHA_MIN: f32 = {ALPHA_MIN!r};",
        "",
    ]
    lines += rust_table("E_CHARLIE", "The albedo of the specification's Charlie BRDF.", charlie)
    lines.append("")
    lines += rust_table("E", "The albedo of raylab's sheen BRDF (at most 1).", used)
    tmp = args.o + ".tmp"
    with open(tmp, "w", encoding="utf-8") as out:
        out.write("\n".join(lines) + "\n")
    os.replace(tmp, args.o)
    print(f"wrote {args.o}", file=sys.stderr)


if __name__ == "__main__":
    main()
