"""tables/mie/mie_fog.py (issue 51 item 3; docs/lidar.md §6): the Mie code against published values and the
Rayleigh limit, and the shipped fog tables (normalisation, asymmetry, shape, made by this code).

Published values: Bohren and Huffman 1983, appendix A, the BHMIE example (water-like sphere m = 1.55, radius
0.525 µm at λ = 0.6328 µm, x = 5.213): Q_ext = Q_sca = 3.10543, Q_back = 2.92534.
Broken variants (run by hand, 2026-11-28): a_n with m·D_n in place of D_n/m fails the BHMIE example (Q_ext off by
0.12) and the Rayleigh limit; π_n's recurrence without its 1/n fails the regeneration check (NaN). Not caught, and
not wrong here: D_n by upward recurrence from cot(mx) (stable for these weakly absorbing droplets; the code keeps
BHMIE's downward recurrence, which is stable for all m).
"""
import math
import os
import re
import sys

import pytest

np = pytest.importorskip("numpy")

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tables", "mie"))
import mie_fog  # noqa: E402

TABLES = ["fog_advection_905nm.csv", "fog_radiation_905nm.csv"]


def test_bhmie_example():
    x = 2.0 * math.pi * 0.525 / 0.6328
    q_ext, q_sca, q_back, g = mie_fog.efficiencies(complex(1.55, 0.0), [x])
    assert abs(q_ext[0] - 3.10543) < 1e-5
    assert abs(q_sca[0] - 3.10543) < 1e-5
    assert abs(q_back[0] - 2.92534) < 1e-5
    assert 0.0 < g[0] < 1.0


@pytest.mark.parametrize("m", [complex(1.328, 6.0e-7), complex(1.55, 0.0), complex(1.5, 0.1)])
def test_rayleigh_limit(m):
    k = (m * m - 1.0) / (m * m + 2.0)
    for x in [1e-3, 1e-2, 3e-2]:
        q_ext, q_sca, q_back, g = mie_fog.efficiencies(m, [x])
        want = 8.0 / 3.0 * x**4 * abs(k) ** 2
        assert abs(q_sca[0] / want - 1.0) < 4.0 * x * x
        assert abs(q_ext[0] - (4.0 * x * k.imag + want)) < 4.0 * x * x * max(q_ext[0], want)
        assert abs(g[0]) < 2.0 * x * x
        # the angular shape: S11 ∝ (1 + cos²θ)/2
        a, b = mie_fog.mie_ab(m, np.array([x]))
        theta = np.radians(np.linspace(0.0, 180.0, 19))
        pi, tau = mie_fog.pi_tau(np.cos(theta), a.shape[1])
        s1, s2 = mie_fog.amplitudes(a, b, pi, tau)
        s11 = 0.5 * (np.abs(s1[0]) ** 2 + np.abs(s2[0]) ** 2)
        shape = (1.0 + np.cos(theta) ** 2) / 2.0
        assert np.max(np.abs(s11 / s11[0] - shape)) < 4.0 * x


def read_table(name):
    path = os.path.join(ROOT, "tables", "mie", name)
    header, rows = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                header.append(line)
            elif line[0].isdigit():
                rows.append([float(v) for v in line.split(",")])
    return "".join(header), np.array(rows)


@pytest.mark.parametrize("name", TABLES)
def test_shipped_table(name):
    header, t = read_table(name)
    theta, p = t[:, 0], t[:, 1]
    assert theta[0] == 0.0 and theta[-1] == 180.0
    assert np.all(np.diff(theta) > 0)
    assert np.all(p >= 0)
    assert np.all(np.diff(theta[theta < 5.0]) <= 0.05 + 1e-9)  # the forward peak resolved
    norm = mie_fog.sphere_integral(theta, p)
    g = mie_fog.sphere_integral(theta, p, cos_weight=True) / norm
    assert abs(norm - 1.0) < 1e-3  # the file is per steradian (dartspp renormalises the interpolant)
    g_header = float(re.search(r"g of this table's interpolant: ([0-9.]+)", header).group(1))
    g_mie = float(re.search(r"asymmetry g \(Mie, exact over the sizes\): ([0-9.]+)", header).group(1))
    assert abs(g - g_header) < 2e-5
    assert abs(g - g_mie) < 2e-4  # the linear interpolant against the exact series
    assert 0.8 < g < 0.9  # fog droplets at 905 nm: strongly forward (Shettle and Fenn's fogs: g ≈ 0.84–0.87)
    albedo = float(re.search(r"single-scattering albedo: ([0-9.]+)", header).group(1))
    assert 0.9998 < albedo < 1.0
    for word in ["Shettle and Fenn 1979", "AFGL-TR-79-0214", "Hale and Querry 1973", "Bohren and Huffman", "0.905"]:
        assert word in header


def test_table_made_by_this_code():
    """The advection table again at a coarse size step (0.05 µm, 10× the shipped one): g within 5e-4 and the
    values within a few percent (the size integration's convergence, not a regression of the file)."""
    _, t = read_table(TABLES[0])
    alpha, b, gamma, r_max = mie_fog.DISTRIBUTIONS["advection"]
    p, g, albedo, _, _ = mie_fog.polydisperse(alpha, b, gamma, r_max, 0.05, t[:, 0])
    rel = np.abs(p / t[:, 1] - 1.0)
    assert abs(g - 0.86779) < 5e-4
    assert np.median(rel) < 2e-3
    assert rel.max() < 0.1
