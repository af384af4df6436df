"""The tool's rows: their elimination factored once (`factor_tool_rows`), a step's right-hand
sides, the sweep toward the struck end and the substitution toward the working end, each as
`SEGMENTS` independent chains.
"""

from __future__ import annotations

import numpy as np

from ..compiled import compiled
from .bundles import MIN_SEGMENT, SEGMENTS, ToolRows, boundary_weights
from .gravity import weigh_rows
from .working_end import working_end_diagonal


@compiled()
def segment_layout(n):
    """`(length, head)`: nodes `1 … head` are swept serially, nodes `head+1 … n` as `SEGMENTS`
    segments of `length` nodes (none when the tool is too short for them)."""
    length = n // SEGMENTS if n >= SEGMENTS * MIN_SEGMENT else 0
    return length, n - SEGMENTS * length


@compiled()
def factor_tool_rows(tool, rod, weights, medium):
    """Eliminate rows u_N … u_1 once (`ToolRows`): `P`, `1/den`, the coefficient `c` of `Q_{i+1}`
    in `Q_i = rhs_i/den_i + c_i·Q_{i+1}`, and the segments' multiples of their carries: for node i
    of a segment `b … e` (`segment_layout`), `Π c_j` over `i … e` and `Π P_j` over `b … i`.

    Row u_N: `working_end_diagonal·u_N − θ·k_N·u_{N−1} = rhs`, θ the end rows' weight of
    `boundary_weights`.
    Rows u_i: `−w·r·lower_i·u_{i−1} + (1 + w·r·(lower_i + upper_i))·u_i − w·r·upper_i·u_{i+1} = rhs_i`.
    """
    end_weight = boundary_weights(weights, rod.time_step).end_weight
    weight_new, r = weights.new, rod.courant_squared
    grid_lower, grid_upper = tool.lower, tool.upper
    n = len(tool.node_area) - 1
    p = np.zeros(n + 1)
    inv_den = np.zeros(n + 1)
    carry = weight_new * r * grid_upper
    diag_n = working_end_diagonal(tool, rod, weights, medium)
    p[n] = end_weight * rod.working_end_stiffness / diag_n
    inv_den[n] = 1.0 / diag_n
    for i in range(n - 1, 0, -1):
        den = 1.0 + weight_new * r * (grid_lower[i] + grid_upper[i]) - carry[i] * p[i + 1]
        p[i] = weight_new * r * grid_lower[i] / den
        inv_den[i] = 1.0 / den
    coefficient = carry * inv_den
    coefficient[n] = 0.0  # nothing is carried into row u_N
    length, head = segment_layout(n)
    coefficient_product = np.ones(n + 1)
    p_product = np.ones(n + 1)
    for start in range(head + 1, n + 1, max(length, 1)):
        end = start + length - 1
        product = 1.0
        for i in range(end, start - 1, -1):
            product *= coefficient[i]
            coefficient_product[i] = product
        product = 1.0
        for i in range(start, end + 1):
            product *= p[i]
            p_product[i] = product
    return ToolRows(
        p=p, inv_den=inv_den, coefficient=coefficient, coefficient_product=coefficient_product, p_product=p_product
    )


@compiled(inline="always")
def segment_starts(length, head):
    """The segments' length and first nodes, unsigned (`segment_layout`)."""
    size = np.uint64(length)
    b0 = np.uint64(head + 1)
    return size, b0, b0 + size, b0 + np.uint64(2) * size, b0 + np.uint64(3) * size


@compiled(inline="always")
def sweep_toward_struck_end(u, row, rows, length, head):
    """`Q_i = a_i + c_i·Q_{i+1}` for i = n … 1, row `row` of `u` holding `a_i` on entry, with the
    factors `rows` (`ToolRows`) and the segments of `segment_layout`.

    Returns `Q_1` and the true Q carried into each segment (`Q_{e+1}`, e its last node). On return
    the row holds the segments' chains, started from 0 (true: chain + `Π c`·carry), and the head's
    true values.
    """
    coefficient, coefficient_product = rows.coefficient, rows.coefficient_product
    first = 0.0  # Q_{n+1}
    carry_0 = carry_1 = carry_2 = carry_3 = 0.0  # carry_3 stays 0: the last segment ends at row N
    if length > 0:
        size, b0, b1, b2, b3 = segment_starts(length, head)
        s0 = s1 = s2 = s3 = 0.0
        for k in range(size):
            j = size - np.uint64(1) - k
            s0 = u[row, b0 + j] + coefficient[b0 + j] * s0
            u[row, b0 + j] = s0
            s1 = u[row, b1 + j] + coefficient[b1 + j] * s1
            u[row, b1 + j] = s1
            s2 = u[row, b2 + j] + coefficient[b2 + j] * s2
            u[row, b2 + j] = s2
            s3 = u[row, b3 + j] + coefficient[b3 + j] * s3
            u[row, b3 + j] = s3
        carry_2 = u[row, b3] + coefficient_product[b3] * carry_3
        carry_1 = u[row, b2] + coefficient_product[b2] * carry_2
        carry_0 = u[row, b1] + coefficient_product[b1] * carry_1
        first = u[row, b0] + coefficient_product[b0] * carry_0
    for i in range(head, 0, -1):
        first = u[row, i] + coefficient[i] * first
        u[row, i] = first
    return first, (carry_0, carry_1, carry_2, carry_3)


@compiled(inline="always")
def substitute_toward_working_end(u, row, rows, length, head, x_0, carries):
    """`u_i = P_i·u_{i−1} + Q_i` for i = 1 … n from `u_0 = x_0`, row `row` of `u` holding what
    `sweep_toward_struck_end` left, with its carries: the true Q are made on the way."""
    p, coefficient_product, p_product = rows.p, rows.coefficient_product, rows.p_product
    carry_0, carry_1, carry_2, carry_3 = carries
    prev = x_0
    for i in range(1, head + 1):
        prev = p[i] * prev + u[row, i]
        u[row, i] = prev
    if length == 0:
        return
    size, b0, b1, b2, b3 = segment_starts(length, head)
    s0 = s1 = s2 = s3 = 0.0
    for j in range(size):
        s0 = p[b0 + j] * s0 + (u[row, b0 + j] + coefficient_product[b0 + j] * carry_0)
        u[row, b0 + j] = s0
        s1 = p[b1 + j] * s1 + (u[row, b1 + j] + coefficient_product[b1 + j] * carry_1)
        u[row, b1 + j] = s1
        s2 = p[b2 + j] * s2 + (u[row, b2 + j] + coefficient_product[b2 + j] * carry_2)
        u[row, b2 + j] = s2
        s3 = p[b3 + j] * s3 + (u[row, b3 + j] + coefficient_product[b3 + j] * carry_3)
        u[row, b3 + j] = s3
    # Each segment's chain plus `Π P` times the true value before it, segment after segment.
    before = prev
    for start in (b0, b1, b2, b3):
        end = start + size - np.uint64(1)
        after = u[row, end] + p_product[end] * before
        for j in range(size):
            u[row, start + j] += p_product[start + j] * before
        before = after


@compiled(inline="always")
def known_layers(u, layer, i, weight_cur, weight_old):
    """The known layers' combination `v = w_n·u^n + w_{n−1}·u^{n−1}` at nodes i − 1, i, i + 1."""
    _, cur, old, _ = layer
    return (
        weight_cur * u[cur, i - 1] + weight_old * u[old, i - 1],
        weight_cur * u[cur, i] + weight_old * u[old, i],
        weight_cur * u[cur, i + 1] + weight_old * u[old, i + 1],
    )


@compiled(inline="always")
def right_hand_sides(u, increments, layer, tool, rows, rod, weights, step):
    """Right-hand sides of the tool's rows u_1 … u_{N−1} over their diagonals, into row `new` of
    `u` (the sweep turns them into the Q_i there). The known layers enter the operator as one
    combination v (`known_layers`). Each case has a loop of its own: a loop that tests `uniform`
    at every node, as LLVM leaves it, costs about 4% of a step of the paper's scheme on 2000 cells."""
    new, cur, old, _ = layer
    n, r, weight_cur, weight_old = step.n, rod.courant_squared, step.weight_cur, weights.old
    grid_lower, grid_upper, inv_den = tool.lower, tool.upper, rows.inv_den
    if step.explicit:
        explicit_interior(u, increments, layer, tool, r, n)
    elif tool.uniform:
        for i in range(1, n):
            v_left, v_mid, v_right = known_layers(u, layer, i, weight_cur, weight_old)
            lap = v_left - 2.0 * v_mid + v_right
            u[new, i] = (2.0 * u[cur, i] - u[old, i] + r * lap) * inv_den[i]
    else:
        for i in range(1, n):
            v_left, v_mid, v_right = known_layers(u, layer, i, weight_cur, weight_old)
            lap = grid_lower[i] * (v_left - v_mid) + grid_upper[i] * (v_right - v_mid)
            u[new, i] = (2.0 * u[cur, i] - u[old, i] + r * lap) * inv_den[i]


@compiled(inline="always")
def explicit_interior(u, increments, layer, tool, r, n):
    """The explicit scheme's interior nodes 1 … n−1 of the new layer: uncoupled (den_i = 1), the
    weight's lift added (`weigh_rows`).

    In summed form: each node's increment `d = u^m − u^{m−1}` is kept apart from the layers,
    `d ← d + r·Λu^m`, `u^{m+1} = u^m + d`. Written `u^{m+1} = 2u^m − u^{m−1} + r·Λu^m`, the operator,
    the small difference of the strains beside the node, was rounded against a displacement of up
    to tenths of a metre: where the tool barely strains, that rounding grew the tool's sawtooth
    mode by three decades (`bench/sawtooth.py`). Summed, it is rounded against a step's motion."""
    new, cur, _, _ = layer
    grid_lower, grid_upper = tool.lower, tool.upper
    if tool.uniform:
        for i in range(1, n):
            increments[i] += r * (u[cur, i - 1] - 2.0 * u[cur, i] + u[cur, i + 1])
            u[new, i] = u[cur, i] + increments[i]
    else:
        for i in range(1, n):
            increments[i] += r * (
                grid_lower[i] * (u[cur, i - 1] - u[cur, i]) + grid_upper[i] * (u[cur, i + 1] - u[cur, i])
            )
            u[new, i] = u[cur, i] + increments[i]
    weigh_rows(u, increments, new, tool.gravity)


NO_CARRIES = (0.0, 0.0, 0.0, 0.0)


@compiled(inline="always")
def sweep(u, layer, rows, step):
    """The sweep toward the struck end: `(Q_1, carries)`, Q_1 the tool's link to the struck end
    `u_1 = P_1·u_0 + Q_1` (`sweep_toward_struck_end`). The explicit scheme's rows are uncoupled:
    Q_1 is row 1's own right-hand side and nothing is carried."""
    if step.explicit:
        return u[layer.new, 1], NO_CARRIES
    length, head = step.segments
    return sweep_toward_struck_end(u, layer.new, rows, length, head)


@compiled(inline="always")
def back_substitute(u, layer, u_0, carries, rows, step):
    """The substitution toward the working end from the new `u_0`: the new layer in row `new`."""
    if step.explicit:
        n = step.n
        # P_i = 0 but at a massless working end
        u[layer.new, n] = rows.p[n] * u[layer.new, n - 1] + u[layer.new, n]
    else:
        length, head = step.segments
        substitute_toward_working_end(u, layer.new, rows, length, head, u_0, carries)
