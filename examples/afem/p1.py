"""P1 finite elements for the Laplace equation on triangle meshes (numpy/scipy).

Everything is vectorised over the cells: `points` is (N, 2), `cells` is (M, 3)
with vertex ids. The functions here know nothing about bisect or files.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def geometry(points, cells):
    """Areas (M,) and gradients of the barycentric coordinates (M, 3, 2)."""
    p = points[cells]                                  # (M, 3, 2)
    e1 = p[:, 1] - p[:, 0]
    e2 = p[:, 2] - p[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]    # twice the signed area
    # Rows of inv([e1 e2]) are the gradients of lambda_1 and lambda_2.
    g1 = np.stack([e2[:, 1], -e2[:, 0]], axis=1) / det[:, None]
    g2 = np.stack([-e1[:, 1], e1[:, 0]], axis=1) / det[:, None]
    grads = np.stack([-g1 - g2, g1, g2], axis=1)
    return 0.5 * np.abs(det), grads


def edges(cells):
    """Unique edges (E, 2), the edge id of each cell's edge opposite each vertex
    (M, 3), and how many cells share each edge (E,)."""
    local = np.array([[1, 2], [2, 0], [0, 1]])         # edge opposite vertex i
    all_edges = np.sort(cells[:, local].reshape(-1, 2), axis=1)
    unique, inverse, counts = np.unique(all_edges, axis=0, return_inverse=True,
                                        return_counts=True)
    return unique, inverse.reshape(-1, 3), counts


def boundary_vertices(points, cells):
    """Boolean mask (N,) of the vertices on the boundary (ends of edges in one cell)."""
    edge_list, _, counts = edges(cells)
    mask = np.zeros(len(points), dtype=bool)
    mask[edge_list[counts == 1].ravel()] = True
    return mask


def stiffness(points, cells):
    """Global stiffness matrix of the P1 Laplacian (CSR)."""
    area, grads = geometry(points, cells)
    local = area[:, None, None] * np.einsum("mik,mjk->mij", grads, grads)
    rows = np.repeat(cells, 3, axis=1).ravel()
    cols = np.tile(cells, (1, 3)).ravel()
    n = len(points)
    return sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n, n))


def solve_dirichlet(points, cells, g, f=None):
    """u_h in P1 with -Lap u = f, u = g on the whole boundary (g: callable of
    (N, 2) points, interpolated at the boundary vertices). f is ignored when
    None (Laplace); otherwise a callable, integrated with the vertex rule.
    Returns (u_h at the vertices, mask of the free vertices)."""
    K = stiffness(points, cells)
    fixed = boundary_vertices(points, cells)
    free = ~fixed
    u = np.zeros(len(points))
    u[fixed] = g(points[fixed])
    rhs = -K[free][:, fixed] @ u[fixed]
    if f is not None:
        area, _ = geometry(points, cells)
        load = np.zeros(len(points))
        fv = f(points)
        np.add.at(load, cells.ravel(), (np.repeat(area / 3, 3) * fv[cells].ravel()))
        rhs += load[free]
    u[free] = spla.spsolve(K[free][:, free].tocsc(), rhs)
    return u, free


def residual_estimator(points, cells, u, f=None):
    """Residual estimator per cell, eta_T (not squared):
        eta_T^2 = h_T^2 ||f||_T^2 + 1/2 sum_{interior E of T} h_E ||[du_h/dn]||_E^2
    with h_T the diameter (longest edge). The jump of the normal derivative
    is constant on an edge, so ||[du_h/dn]||_E^2 = h_E [du_h/dn]^2. Dirichlet
    data oscillation is not included. f (callable or None) is integrated with
    the centroid rule."""
    area, grads = geometry(points, cells)
    grad_u = np.einsum("mi,mik->mk", u[cells], grads)          # (M, 2)
    edge_list, cell_edges, counts = edges(cells)
    vec = points[edge_list[:, 1]] - points[edge_list[:, 0]]
    h_e = np.linalg.norm(vec, axis=1)
    normal = np.stack([vec[:, 1], -vec[:, 0]], axis=1) / h_e[:, None]
    # Sum of the signed normal derivatives of the (at most two) cells at each
    # edge, with opposite orientation for the two sides: the jump.
    side = np.einsum("mk,mjk->mj", grad_u, normal[cell_edges])  # (M, 3)
    # Orientation: +1 if the cell lies to the left of the edge's normal.
    centroid = points[cells].mean(axis=1)
    mid = 0.5 * (points[edge_list[:, 0]] + points[edge_list[:, 1]])
    to_cell = centroid[:, None, :] - mid[cell_edges]
    sign = np.sign(np.einsum("mjk,mjk->mj", to_cell, normal[cell_edges]))
    jump = np.zeros(len(edge_list))
    np.add.at(jump, cell_edges.ravel(), (sign * side).ravel())
    jump[counts == 1] = 0.0                                      # boundary edges
    eta2 = 0.5 * np.sum(h_e[cell_edges] ** 2 * jump[cell_edges] ** 2, axis=1)
    if f is not None:
        h_t = h_e[cell_edges].max(axis=1)
        eta2 += h_t ** 2 * area * f(centroid) ** 2
    return np.sqrt(eta2)


def collapsed_gauss(n):
    """A degree 2n-1 rule on the reference triangle (0,0), (1,0), (0,1): Gauss-
    Legendre on the square collapsed (Duffy) onto the vertex (1,0), so the
    points crowd there. Returns barycentric coordinates (Q, 3) and weights
    (Q,) summing to 1 (multiply by the area)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x = 0.5 * (x + 1)
    w = 0.5 * w
    s, t = np.meshgrid(x, x, indexing="ij")
    ws, wt = np.meshgrid(w, w, indexing="ij")
    xi = s.ravel()
    eta = (t * (1 - s)).ravel()
    weight = (ws * wt * (1 - s)).ravel() * 2.0            # reference area 1/2
    bary = np.stack([1 - xi - eta, xi, eta], axis=1)
    return bary, weight


def h1_error(points, cells, u, grad_exact, singular_point=(0.0, 0.0), order=6):
    """|u - u_h|_{H^1} by quadrature: a collapsed Gauss rule with `order`^2
    points per cell, collapsed onto each cell's vertex nearest to
    `singular_point`, so the cell at a corner singularity is integrated well."""
    area, grads = geometry(points, cells)
    grad_u = np.einsum("mi,mik->mk", u[cells], grads)
    # Roll each cell's vertices so the vertex nearest the singularity is local 1
    # (the collapse vertex of the rule); the triangle itself is unchanged.
    dist = np.linalg.norm(points[cells] - np.asarray(singular_point), axis=2)
    shift = (np.argmin(dist, axis=1) - 1) % 3
    idx = (np.arange(3)[None, :] + shift[:, None]) % 3
    rolled = np.take_along_axis(cells, idx, axis=1)
    bary, weight = collapsed_gauss(order)
    q = np.einsum("qi,mik->mqk", bary, points[rolled])         # (M, Q, 2)
    diff = grad_exact(q.reshape(-1, 2)).reshape(q.shape) - grad_u[:, None, :]
    err2 = area * np.einsum("q,mq->m", weight, np.sum(diff ** 2, axis=2))
    return np.sqrt(err2.sum())


def fitted_slope(x, y):
    """Least-squares slope of log(y) against log(x)."""
    return np.polyfit(np.log(x), np.log(y), 1)[0]
