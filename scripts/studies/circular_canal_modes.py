#!/usr/bin/python3
"""Sloshing frequencies of a half-full horizontal circular canal, by finite elements.

The reference of cases/sloshing_circular_2d.yaml: linear potential flow in the lower half of a
circle of radius R, no flux through the wall, and on the free surface y = 0 the condition
phi_y = (omega^2 / g) phi. In weak form (P1 elements on a polar mesh of the half disc)
K phi = lambda M_s phi, K the Laplacian's stiffness, M_s the mass matrix of the surface,
lambda = omega^2 R / g. The interior is condensed onto the surface nodes and the small dense
problem solved. McIver (1989, J. Fluid Mech. 201) gives 1.3557 for the first (antisymmetric) mode;
this script prints each mode's lambda at three meshes (1.35648, 1.35592, 1.35577: it converges to
McIver's value).

Usage: /usr/bin/python3 scripts/studies/circular_canal_modes.py
"""
import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.spatial import Delaunay


def modes(rings, per_ring, count=3):
    """The first `count` nonzero lambda = omega^2 R / g on a mesh of `rings` rings (R = 1)."""
    points = [(0.0, 0.0)]
    for i in range(1, rings + 1):
        r, n = i / rings, per_ring * i
        for j in range(n + 1):
            theta = -np.pi * j / n
            points.append((r * np.cos(theta), r * np.sin(theta)))
    points = np.array(points)
    rows, cols, values = [], [], []
    for t in Delaunay(points).simplices:
        p = points[t]
        area = 0.5 * abs(np.linalg.det(np.c_[p[1] - p[0], p[2] - p[0]]))
        if area < 1e-14:
            continue
        grad = np.linalg.inv(np.c_[np.ones(3), p])[1:, :]  # the basis functions' gradients
        k = area * grad.T @ grad
        for a in range(3):
            for b in range(3):
                rows.append(t[a]), cols.append(t[b]), values.append(k[a, b])
    n = len(points)
    K = sp.coo_matrix((values, (rows, cols)), shape=(n, n)).tocsr()
    surface = np.where(np.abs(points[:, 1]) < 1e-12)[0]
    surface = surface[np.argsort(points[surface, 0])]
    M = np.zeros((len(surface), len(surface)))
    for k in range(len(surface) - 1):
        length = points[surface[k + 1], 0] - points[surface[k], 0]
        M[k:k + 2, k:k + 2] += length / 6 * np.array([[2, 1], [1, 2]])
    inner = np.setdiff1d(np.arange(n), surface)
    Ksi = K[surface][:, inner]
    condensed = K[surface][:, surface].toarray() - Ksi @ sla.spsolve(K[inner][:, inner].tocsc(), Ksi.T.toarray())
    lam = la.eigh(condensed, M, eigvals_only=True)
    return lam[1:count + 1]  # lam[0] = 0: the constant potential


if __name__ == "__main__":
    for rings in (20, 40, 80):
        print("%2d rings: omega^2 R / g =" % rings, " ".join("%.5f" % v for v in modes(rings, 8)))
