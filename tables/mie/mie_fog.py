#!/usr/bin/env python3
"""Mie phase functions of fog for dartspp's tabulated phase function (docs/lidar.md §6).

Writes tables/mie/fog_advection_905nm.csv and tables/mie/fog_radiation_905nm.csv: "theta_deg,value" rows, the
phase function of a fog droplet size distribution at 905 nm per steradian (normalised: ∫ p dω = 1), with a
comment header naming the sources and the figures.

The Mie code is our own, after Bohren and Huffman, "Absorption and Scattering of Light by Small Particles"
(Wiley 1983), ch. 4 and the BHMIE program of its appendix A:
  - the logarithmic derivative D_n(mx) by downward recurrence D_{n-1} = n/y − 1/(D_n + n/y) from an order
    well above the last one used (BH eq. 4.89; BHMIE starts at max(n_stop, |mx|) + 15 with D = 0),
  - the Riccati–Bessel functions ψ_n(x) = x j_n(x) and ξ_n(x) = x h_n^(1)(x) by upward recurrence
    (BH eq. 4.88, ψ_{-1} = cos x, ψ_0 = sin x, χ_{-1} = −sin x, χ_0 = cos x, ξ = ψ − iχ),
  - a_n, b_n from BH eq. 4.88: a_n = ((D_n/m + n/x) ψ_n − ψ_{n−1}) / ((D_n/m + n/x) ξ_n − ξ_{n−1}) and
    b_n likewise with m D_n,
  - the amplitudes S1, S2 from π_n, τ_n (BH eq. 4.74 and 4.47) and the efficiencies Q_ext, Q_sca, Q_back,
    and g·Q_sca (BH eq. 4.61, 4.62, 4.82 and 4.70),
  - the series cut at n_stop = x + 4 x^(1/3) + 2 (Wiscombe 1980, as BHMIE).

The size distribution is the modified gamma distribution of Shettle and Fenn, "Models for the aerosols of the lower
atmosphere and the effects of humidity variations on their optical properties", AFGL-TR-79-0214 (1979):
n(r) ∝ r^α exp(−b r^γ), r in µm, for
  advection fog: α = 3, b = 0.3 µm⁻¹, γ = 1 (mode radius α/b = 10 µm),
  radiation fog: α = 6, b = 1.5 µm⁻¹, γ = 1 (mode radius 4 µm).
The refractive index of water at 905 nm: m = 1.328 + 6.0e-7 i, Hale and Querry, "Optical constants of water in the
200-nm to 200-µm wavelength region", Appl. Opt. 12, 555 (1973), Table 1, linearly between its 0.900 µm row
(1.328, 4.86e-7) and its 0.925 µm row (1.328, 1.06e-6) (as tabulated in the refractiveindex.info database,
H2O/Hale.yml). The absorption is negligible at this wavelength: the albedo differs from 1 by ~1e-4.

Python 3 and numpy only. `python3 tables/mie/mie_fog.py` rewrites the two tables (about 40 s on one core);
tests/python/test_mie_fog.py checks the Mie code against Bohren and Huffman's published BHMIE example and the
Rayleigh limit, and the shipped tables' normalisation and asymmetry.
"""
import argparse
import os
import sys

import numpy as np

LAMBDA_UM = 0.905
M_WATER = complex(1.328, 6.0e-7)

DISTRIBUTIONS = {
    # name: (alpha, b [1/µm], gamma, r_max [µm] where r^(alpha+2) exp(-b r) is < 1e-7 of its peak)
    "advection": (3.0, 0.3, 1.0, 100.0),
    "radiation": (6.0, 1.5, 1.0, 30.0),
}


def n_stop(x):
    return int(np.floor(x + 4.0 * np.cbrt(x) + 2.0))


def mie_ab(m, x):
    """The coefficients a_n, b_n (n = 1..n_stop) for each size parameter of x (a 1-D array), as one (len(x),
    n_max) array each, zero beyond a size's own n_stop."""
    x = np.atleast_1d(np.asarray(x, dtype=float))
    nst = np.array([n_stop(xi) for xi in x])
    n_max = int(nst.max())
    y = m * x
    n_mx = int(max(n_max, np.abs(y).max())) + 16
    # D_n(y), downward from n_mx (D = 0 there: the recurrence forgets its start; BH appendix A)
    d = np.zeros((len(x), n_mx + 1), dtype=complex)
    for n in range(n_mx, 0, -1):
        d[:, n - 1] = n / y - 1.0 / (d[:, n] + n / y)
    a = np.zeros((len(x), n_max), dtype=complex)
    b = np.zeros((len(x), n_max), dtype=complex)
    psi0, psi1 = np.cos(x), np.sin(x)
    chi0, chi1 = -np.sin(x), np.cos(x)
    xi1 = psi1 - 1j * chi1
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, n_max + 1):
            psi = (2.0 * n - 1.0) * psi1 / x - psi0
            chi = (2.0 * n - 1.0) * chi1 / x - chi0
            xi = psi - 1j * chi
            dn = d[:, n]
            ta = dn / m + n / x
            tb = m * dn + n / x
            an = (ta * psi - psi1) / (ta * xi - xi1)
            bn = (tb * psi - psi1) / (tb * xi - xi1)
            keep = n <= nst  # beyond n_stop χ overflows upward; the terms are negligible there (BHMIE stops)
            a[:, n - 1] = np.where(keep, an, 0.0)
            b[:, n - 1] = np.where(keep, bn, 0.0)
            psi0, psi1 = psi1, psi
            chi0, chi1 = chi1, chi
            xi1 = psi1 - 1j * chi1
    return a, b


def efficiencies(m, x):
    """Q_ext, Q_sca, Q_back and g for each size parameter of x (BH eq. 4.61, 4.62, 4.82, 4.70)."""
    x = np.atleast_1d(np.asarray(x, dtype=float))
    a, b = mie_ab(m, x)
    n = np.arange(1, a.shape[1] + 1, dtype=float)
    f = 2.0 * n + 1.0
    q_ext = 2.0 / x**2 * np.sum(f * (a + b).real, axis=1)
    q_sca = 2.0 / x**2 * np.sum(f * (np.abs(a) ** 2 + np.abs(b) ** 2), axis=1)
    sign = (-1.0) ** n
    q_back = np.abs(np.sum(f * sign * (a - b), axis=1)) ** 2 / x**2
    # g Q_sca = 4/x² [Σ n(n+2)/(n+1) Re(a_n a*_{n+1} + b_n b*_{n+1}) + Σ (2n+1)/(n(n+1)) Re(a_n b*_n)]
    t1 = (n[:-1] * (n[:-1] + 2.0) / (n[:-1] + 1.0)) * (a[:, :-1] * np.conj(a[:, 1:]) + b[:, :-1] * np.conj(b[:, 1:])).real
    t2 = (f / (n * (n + 1.0))) * (a * np.conj(b)).real
    g = 4.0 / x**2 * (np.sum(t1, axis=1) + np.sum(t2, axis=1)) / q_sca
    return q_ext, q_sca, q_back, g


def pi_tau(mu, n_max):
    """π_n(μ) and τ_n(μ), n = 1..n_max, as (n_max, len(mu)) arrays (BH eq. 4.47)."""
    mu = np.asarray(mu, dtype=float)
    pi = np.zeros((n_max, len(mu)))
    tau = np.zeros((n_max, len(mu)))
    p_prev, p = np.zeros_like(mu), np.ones_like(mu)  # π_0, π_1
    for n in range(1, n_max + 1):
        pi[n - 1] = p
        tau[n - 1] = n * mu * p - (n + 1.0) * p_prev
        p_next = ((2.0 * n + 1.0) * mu * p - (n + 1.0) * p_prev) / n
        p_prev, p = p, p_next
    return pi, tau


def amplitudes(a, b, pi, tau):
    """S1, S2 (len(sizes), len(angles)) from a_n, b_n (BH eq. 4.74)."""
    n = np.arange(1, a.shape[1] + 1, dtype=float)
    f = (2.0 * n + 1.0) / (n * (n + 1.0))
    fa, fb = a * f, b * f
    s1 = fa @ pi[: a.shape[1]] + fb @ tau[: a.shape[1]]
    s2 = fa @ tau[: a.shape[1]] + fb @ pi[: a.shape[1]]
    return s1, s2


def angle_grid():
    """0–5° by 0.05° (the forward peak), 5–20° by 0.2°, 20–180° by 0.5°."""
    return np.unique(np.concatenate([np.linspace(0.0, 5.0, 101), np.linspace(5.0, 20.0, 76), np.linspace(20.0, 180.0, 321)]))


def size_grid(r_max, dr):
    """Radii (µm) and trapezoid weights on [dr, r_max]."""
    r = np.arange(dr, r_max + 0.5 * dr, dr)
    w = np.full_like(r, dr)
    w[0] = w[-1] = 0.5 * dr
    return r, w


def polydisperse(alpha, b_, gamma, r_max, dr, theta_deg, m=M_WATER, lam=LAMBDA_UM, chunk=400):
    """The size-averaged phase function p(θ) per steradian, g, the albedo and the mean cross sections."""
    r, w = size_grid(r_max, dr)
    nr = w * r**alpha * np.exp(-b_ * r**gamma)  # n(r) dr, unnormalised
    k = 2.0 * np.pi / lam
    x = k * r
    mu = np.cos(np.radians(theta_deg))
    pi, tau = pi_tau(mu, n_stop(x.max()))
    s11 = np.zeros(len(theta_deg))
    c_sca = c_ext = gc = 0.0
    for i in range(0, len(r), chunk):
        xs = x[i:i + chunk]
        a, b = mie_ab(m, xs)
        s1, s2 = amplitudes(a, b, pi, tau)
        s11 += (nr[i:i + chunk] @ (0.5 * (np.abs(s1) ** 2 + np.abs(s2) ** 2)))
        q_ext, q_sca, _, g = efficiencies(m, xs)
        geo = np.pi * r[i:i + chunk] ** 2 * nr[i:i + chunk]
        c_sca += np.sum(geo * q_sca)
        c_ext += np.sum(geo * q_ext)
        gc += np.sum(geo * q_sca * g)
    p = s11 / (k**2 * c_sca)  # BH eq. 3.14 & 4.77: dC_sca/dΩ = S11/k², p = (dC_sca/dΩ)/C_sca
    mass = np.sum(nr)
    return p, gc / c_sca, c_sca / c_ext, c_sca / mass, c_ext / mass


def sphere_integral(theta_deg, p, cos_weight=False):
    """2π ∫ p (cosθ) sinθ dθ of the interpolant linear in θ, by 16-point Gauss–Legendre per interval."""
    th = np.radians(theta_deg)
    xg, wg = np.polynomial.legendre.leggauss(16)
    total = 0.0
    for i in range(len(th) - 1):
        h = th[i + 1] - th[i]
        t = th[i] + 0.5 * h * (xg + 1.0)
        pv = p[i] + (p[i + 1] - p[i]) * (t - th[i]) / h
        f = pv * np.sin(t) * (np.cos(t) if cos_weight else 1.0)
        total += 0.5 * h * np.sum(wg * f)
    return 2.0 * np.pi * total


def write_table(path, name, alpha, b_, gamma, r_max, dr, theta, p, g, albedo, c_sca, c_ext, g_table, norm):
    with open(path, "w") as f:
        f.write("# Phase function of %s fog at 905 nm for dartspp (phase_function type tabulated; docs/lidar.md §6)\n" % name)
        f.write("# written by tables/mie/mie_fog.py (Mie theory after Bohren and Huffman 1983, ch. 4, BHMIE; our own code)\n")
        f.write("# size distribution: modified gamma n(r) ∝ r^%g exp(-%g r^%g), r in µm (Shettle and Fenn 1979,\n" % (alpha, b_, gamma))
        f.write("#   AFGL-TR-79-0214, %s fog model), mode radius %g µm\n" % (name, alpha / (b_ * gamma)))
        f.write("# size integration: trapezoid rule over r from %g to %g µm in steps of %g µm (%d radii)\n"
                % (dr, r_max, dr, int(round(r_max / dr))))
        f.write("# wavelength 0.905 µm; water m = %.3f + %.1e i (Hale and Querry 1973, Appl. Opt. 12, 555, Table 1,\n"
                % (M_WATER.real, M_WATER.imag))
        f.write("#   linear between 0.900 and 0.925 µm)\n")
        f.write("# asymmetry g (Mie, exact over the sizes): %.5f; g of this table's interpolant: %.5f\n" % (g, g_table))
        f.write("# single-scattering albedo: %.8f\n" % albedo)
        f.write("# mean cross sections per droplet: scattering %.6g µm², extinction %.6g µm²\n" % (c_sca, c_ext))
        f.write("# value: p(theta) per steradian (2π ∫ p sinθ dθ of the linear interpolant = %.6f; dartspp renormalises)\n" % norm)
        f.write("# angles: 0-5° by 0.05°, 5-20° by 0.2°, 20-180° by 0.5°; dartspp interpolates linearly in theta\n")
        f.write("theta_deg,value\n")
        for t, v in zip(theta, p):
            f.write("%.2f,%.9e\n" % (t, v))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dr", type=float, default=0.005, help="radius step in µm (default 0.005)")
    ap.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)), help="output folder")
    ap.add_argument("--only", choices=sorted(DISTRIBUTIONS), help="one distribution only")
    a = ap.parse_args()
    theta = angle_grid()
    for name, (alpha, b_, gamma, r_max) in sorted(DISTRIBUTIONS.items()):
        if a.only and name != a.only:
            continue
        p, g, albedo, c_sca, c_ext = polydisperse(alpha, b_, gamma, r_max, a.dr, theta)
        norm = sphere_integral(theta, p)
        g_table = sphere_integral(theta, p, cos_weight=True) / norm
        path = os.path.join(a.out, "fog_%s_905nm.csv" % name)
        write_table(path, name, alpha, b_, gamma, r_max, a.dr, theta, p, g, albedo, c_sca, c_ext, g_table, norm)
        print("%s: g %.5f (table %.5f), albedo %.8f, ∫p dω %.6f, p(0) %.4g /sr, p(180) %.4g /sr -> %s"
              % (name, g, g_table, albedo, norm, p[0], p[-1], path))
    return 0


if __name__ == "__main__":
    sys.exit(main())
