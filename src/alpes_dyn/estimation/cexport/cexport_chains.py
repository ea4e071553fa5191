"""The model's C code per chain, the chains of one structure run side by side (issue 20, item 1).

The EKF's exported C (:mod:`~alpes_dyn.estimation.cexport.cexport_ekf`) calls the model -- the RK4 step, its Jacobian
A and the noise's share N -- once per sample. On the hand, CasADi's generated code of it is one straight-line
function of tens of thousands of operations (more machine code than the processor's instruction cache holds):
the larger half of the step's time. Its outputs fall into independent blocks (:func:`model_blocks`: the hand's five
chains, the states A and N couple), and the four fingers' blocks are the same computation on other inputs.

:func:`chain_model_source` writes the model as C from the instructions of CasADi's own function of each block:
the blocks whose instructions are the same (the same operations on the same places, their constants aside) share
one function that runs them side by side, each operation a loop over the blocks (lanes: the compiler's vector
instructions where it makes them), its constants a table where they differ. The same operations on the same
numbers in the same order as CasADi's code of the whole model: the same results to the last bit (tested against
the filter's ``run``). No heap, no global state; the calling convention of CasADi's generated functions.

Supported operations: those of the Alpes models' dynamics (:data:`_C_OPS`); a model with another one (or a single
block) returns None and keeps CasADi's code.
"""

from __future__ import annotations

from typing import Any

import casadi as cs

__all__ = ["components", "model_blocks", "chain_model_source"]

_C_OPS: dict[int, str] = {
    cs.OP_ASSIGN: "{0}", cs.OP_ADD: "{0}+{1}", cs.OP_SUB: "{0}-{1}", cs.OP_MUL: "{0}*{1}",
    cs.OP_DIV: "{0}/{1}", cs.OP_NEG: "-{0}", cs.OP_TWICE: "2.*{0}", cs.OP_SQ: "{0}*{0}", cs.OP_INV: "1./{0}",
    cs.OP_SQRT: "sqrt({0})", cs.OP_SIN: "sin({0})", cs.OP_COS: "cos({0})", cs.OP_TAN: "tan({0})",
    cs.OP_EXP: "exp({0})", cs.OP_LOG: "log({0})", cs.OP_TANH: "tanh({0})", cs.OP_ATAN: "atan({0})",
    cs.OP_SINH: "sinh({0})", cs.OP_COSH: "cosh({0})", cs.OP_FABS: "fabs({0})", cs.OP_ATAN2: "atan2({0},{1})",
}
"""CasADi's operations as C (the expressions of CasADi's code generator and virtual machine: x*x for sq, 2.*x
for twice, 1./x for inv)."""


def components(n: int, pairs: Any) -> list[int]:
    """The connected components of n items joined by ``pairs`` (i, j): each item's, numbered by their first item.

    Parameters
    ----------
    n : int
        The number of items.
    pairs : iterable of (int, int)
        The pairs joined.

    Returns
    -------
    list of int
        Each item's component.
    """
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, j in pairs:
        parent[root(int(i))] = root(int(j))
    first: dict[int, int] = {}
    return [first.setdefault(root(i), len(first)) for i in range(n)]


def model_blocks(f: cs.Function, n_states: int, state_input: int = 0) -> list[int]:
    """Each state's block: the connected components of the states that ``f``'s outputs couple -- an output
    nonzero in row i that depends on state k joins i and k, an entry (i, j) of a square output joins i and j
    (outputs with ``n_states`` rows) -- numbered by their first state. ``f``'s input ``state_input`` is the
    state.

    Parameters
    ----------
    f : casadi.Function
        The model's function.
    n_states : int
        The state's length.
    state_input : int, optional
        The index of ``f``'s input that is the state (default 0).

    Returns
    -------
    list of int
        Each state's block.
    """
    pairs = []
    for o in range(f.n_out()):
        if f.size1_out(o) != n_states:
            continue
        sp = f.sparsity_out(o)
        rows = sp.row()
        dep = f.jac_sparsity(o, state_input, True)  # (nonzeros of output o, states)
        colind, drow = dep.colind(), dep.row()
        pairs += [(rows[drow[a]], k) for k in range(n_states) for a in range(colind[k], colind[k + 1])]
        if f.size2_out(o) == n_states:  # a square output (A, N)
            pairs += [(rows[a], j) for j in range(n_states) for a in range(sp.colind()[j], sp.colind()[j + 1])]
    return components(n_states, pairs)


def _program(f: cs.Function) -> tuple[list[tuple[Any, ...]], list[tuple[int, int]], list[float]]:
    """``f``'s instructions as (op, outputs, inputs) with its inputs' places (arg, nz) numbered locally, the
    sorted list of those places, and its constants in order."""
    ins = sorted({tuple(f.instruction_input(k)) for k in range(f.n_instructions())
                  if f.instruction_id(k) == cs.OP_INPUT})
    local = {p: i for i, p in enumerate(ins)}
    prog, consts = [], []
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        if op == cs.OP_INPUT:
            prog.append((op, tuple(f.instruction_output(k)), (local[tuple(f.instruction_input(k))],)))
        elif op == cs.OP_CONST:
            prog.append((op, tuple(f.instruction_output(k)), ()))
            consts.append(float(f.instruction_constant(k)))
        else:
            prog.append((op, tuple(f.instruction_output(k)), tuple(f.instruction_input(k))))
    return prog, list(ins), consts


def _constants(consts: list[list[float]]) -> tuple[list[int | None], list[list[float]]]:
    """The constants of the blocks of one structure (consts[block][k]): for each k, None where all blocks have the
    same (bit for bit), else its place among the blocks' own constants; and those own constants by block."""
    slots: list[int | None] = []
    own: list[list[float]] = [[] for _ in consts]
    for k in range(len(consts[0])):
        vals = [v[k] for v in consts]
        if all(repr(v) == repr(vals[0]) for v in vals):
            slots.append(None)
        else:
            slots.append(len(own[0]))
            for o, v in zip(own, vals):
                o.append(v)
    return slots, own


def _template(name: str, prog: list[tuple[Any, ...]], consts: list[float], slots: list[int | None]) -> str:
    """The C function ``name(x, y, c)`` running ``prog`` on one block: x its inputs, y its outputs (its work in
    local variables, as CasADi's code), c the block's own constants (``slots``: :func:`_constants`), ``consts``
    the constants of a block (where they are shared)."""
    lines, k = [], 0
    for op, out, inp in prog:
        if op == cs.OP_INPUT:
            rhs = f"x[{inp[0]}]"
        elif op == cs.OP_OUTPUT:
            lines.append(f"  y[{out[1]}]=a{inp[0]};")
            continue
        elif op == cs.OP_CONST:
            v, slot = consts[k], slots[k]
            k += 1
            rhs = f"c[{slot}]" if slot is not None else (repr(v) if v >= 0 else f"({v!r})")
        else:
            rhs = _C_OPS[op].format(*(f"(a{i})" for i in inp))
        lines.append(f"  a{out[0]}={rhs};")
    return f"static void {name}(const double* x, double* y, const double* c) {{\n{_declare(prog, 'double')}" \
        "  (void)c;\n" + "\n".join(lines) + "\n}\n"


def _declare(prog: list[tuple[Any, ...]], ctype: str) -> str:
    """The declarations of ``prog``'s work variables a<slot>."""
    slots = sorted({out[0] for op, out, _ in prog if op != cs.OP_OUTPUT})
    return "".join(f"  {ctype} {', '.join(f'a{k}' for k in slots[i:i + 12])};\n" for i in range(0, len(slots), 12))


_LANE_OPS: dict[int, str] = {
    cs.OP_ASSIGN: "{0}", cs.OP_ADD: "{0}+{1}", cs.OP_SUB: "{0}-{1}", cs.OP_MUL: "{0}*{1}", cs.OP_DIV: "{0}/{1}",
    cs.OP_NEG: "-{0}", cs.OP_TWICE: "(alpes_lanes)ALPES_BC(2.)*{0}", cs.OP_SQ: "{0}*{0}",
    cs.OP_INV: "(alpes_lanes)ALPES_BC(1.)/{0}",
}
"""The operations a vector of lanes does at once (GCC's and Clang's vector extensions: the same IEEE operation in
each lane); the others run lane by lane (:data:`_LANE_FUNCTIONS`)."""

_LANE_FUNCTIONS: dict[int, str] = {
    cs.OP_SQRT: "sqrt", cs.OP_SIN: "sin", cs.OP_COS: "cos", cs.OP_TAN: "tan", cs.OP_EXP: "exp", cs.OP_LOG: "log",
    cs.OP_TANH: "tanh", cs.OP_ATAN: "atan", cs.OP_SINH: "sinh", cs.OP_COSH: "cosh", cs.OP_FABS: "fabs",
    cs.OP_ATAN2: "atan2",
}

_LANES_HEAD = r"""#include <string.h>
#if (defined(__GNUC__) || defined(__clang__)) && !defined(ALPES_NO_LANES) && !defined(ALPES_VL)
/* the blocks of one structure side by side in vector variables: 4 lanes with AVX, else 2 (SSE2, NEON) */
#if defined(__AVX__) && !defined(ALPES_LANES_2)
#define ALPES_VL 4
typedef double alpes_lanes __attribute__((vector_size(32)));
#define ALPES_BC(c) {c, c, c, c}
#define ALPES_MAP(f, x) {f(x[0]), f(x[1]), f(x[2]), f(x[3])}
#define ALPES_MAP2(f, x, y) {f(x[0], y[0]), f(x[1], y[1]), f(x[2], y[2]), f(x[3], y[3])}
#define ALPES_OWN(c, j) {c[0][j], c[1][j], c[2][j], c[3][j]}
#else
#define ALPES_VL 2
typedef double alpes_lanes __attribute__((vector_size(16)));
#define ALPES_BC(c) {c, c}
#define ALPES_MAP(f, x) {f(x[0]), f(x[1])}
#define ALPES_MAP2(f, x, y) {f(x[0], y[0]), f(x[1], y[1])}
#define ALPES_OWN(c, j) {c[0][j], c[1][j]}
#endif
#endif
#ifdef ALPES_VL
#define ALPES_LANES 1
#endif
"""


def _lane_template(name: str, prog: list[tuple[Any, ...]], consts: list[float], slots: list[int | None]) -> str:
    """The C function ``name(x, y, c)`` running ``prog`` on ALPES_VL lanes at once in variables of type
    ``alpes_lanes`` (:data:`_LANES_HEAD`): x[i*ALPES_VL + l] its inputs, y[m*ALPES_VL + l] its outputs, c[l] lane
    l's own constants (``slots``: :func:`_constants`); ``consts``: a block's constants (where they are shared)."""
    lines, k = [], 0
    for op, out, inp in prog:
        if op == cs.OP_INPUT:
            lines.append(f"  memcpy(&a{out[0]}, x + ALPES_VL * {inp[0]}, sizeof(a{out[0]}));")
            continue
        if op == cs.OP_OUTPUT:
            lines.append(f"  memcpy(y + ALPES_VL * {out[1]}, &a{inp[0]}, sizeof(a{inp[0]}));")
            continue
        if op == cs.OP_CONST:
            v, slot = consts[k], slots[k]
            k += 1
            rhs = f"(alpes_lanes)ALPES_OWN(c, {slot})" if slot is not None else f"(alpes_lanes)ALPES_BC({v!r})"
        elif op in _LANE_OPS:
            rhs = _LANE_OPS[op].format(*(f"a{i}" for i in inp))
        else:
            fn = _LANE_FUNCTIONS[op]
            rhs = f"(alpes_lanes)ALPES_MAP{'2' if len(inp) == 2 else ''}({fn}, {', '.join(f'a{i}' for i in inp)})"
        lines.append(f"  a{out[0]}={rhs};")
    return (f"static void {name}(const double* x, double* y, const double* const* c) {{\n"
            f"{_declare(prog, 'alpes_lanes')}  (void)c;\n" + "\n".join(lines) + "\n}\n")


_Member = tuple[list[tuple[int, int]], list[float], list[tuple[int, int]]]
"""A block of a structure: its input places (arg, nz), its constants, its output places (res, nz)."""


def chain_model_source(f: cs.Function, block: list[int], name: str) -> tuple[str, int] | None:
    """C source of ``name(arg, res, iw, w, mem)``, ``f``'s computation (CasADi's calling convention; all its
    outputs requested) by blocks, the blocks of one structure by one function; and the doubles of work it needs.
    ``block``: each state's block (:func:`model_blocks`); an output nonzero belongs to its row's block (outputs
    with one row per state). None when there is one block, an output that is not one row per state, a block's
    computation reading another's states, or an operation outside :data:`_C_OPS`.

    Parameters
    ----------
    f : casadi.Function
        The model's function.
    block : list of int
        Each state's block (:func:`model_blocks`).
    name : str
        The C function's name.

    Returns
    -------
    tuple of (str, int) or None
        (source, doubles of work), or None.
    """
    nz, nb = len(block), max(block) + 1
    if nb < 2 or any(f.size1_out(o) != nz for o in range(f.n_out())):
        return None
    outs = f.call(f.sx_in())
    per_block: list[list[tuple[int, int, Any]]] = [[] for _ in range(nb)]
    for o, X in enumerate(outs):
        rows = X.sparsity().row()
        for a in range(X.nnz()):
            per_block[block[rows[a]]].append((o, a, X.nz[a]))
    groups: dict[tuple[Any, ...], list[_Member]] = {}
    for b in range(nb):
        fb = cs.Function(f"{name}_b{b}", f.sx_in(), [cs.vertcat(*[e for _, _, e in per_block[b]])])
        prog, ins, consts = _program(fb)
        if any(op not in _C_OPS and op not in (cs.OP_INPUT, cs.OP_OUTPUT, cs.OP_CONST) for op, _, _ in prog):
            return None
        if any(arg == 0 and block[i] != b for arg, i in ins):
            return None  # reads another block's states
        if any(c != c or abs(c) == float("inf") for c in consts):
            return None
        key = (tuple(prog), len(ins), len(per_block[b]), fb.sz_w())
        groups.setdefault(key, []).append((ins, consts, [(o, a) for o, a, _ in per_block[b]]))
    parts, calls, nwork = [], [], 0
    for g, (key, members) in enumerate(groups.items()):
        parts_g, calls_g, nwork_g = _group_source(f"{name}_t{g}", list(key[0]), key[1], key[2], members)
        parts.append(parts_g)
        calls.append(calls_g)
        nwork = max(nwork, nwork_g)
    lanes = ", ".join(str(len(mb)) for mb in groups.values())
    head = (f"\n/* ---- alpes_dyn: the model by blocks ({nb} blocks, {len(groups)} structure(s), lanes {lanes}): "
            "CasADi's instructions of each block, the same operations in the same order ---- */\n")
    head += _LANES_HEAD
    wrapper = (f"int {name}(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{\n"
               "  int i, l;\n  (void)iw;\n  (void)mem;\n" + "\n".join(calls) + "\n  return 0;\n}\n")
    return head + "\n".join(parts) + "\n" + wrapper, nwork


def _group_source(name: str, prog: list[tuple[Any, ...]], ni: int, m: int,
                  members: list[_Member]) -> tuple[str, str, int]:
    """The C of one structure's blocks (members: each block's input places, constants and output places): its
    functions and tables, the wrapper's lines that gather the inputs, call it and scatter the outputs, and the
    doubles of work they need. With several blocks, under ALPES_LANES ALPES_VL blocks at a time in vector
    variables (the spare lanes a copy of the first block), else one call per block."""
    L = len(members)
    slots, own = _constants([c for _, c, _ in members])
    no = max(len(own[0]), 1)
    first = members[0][1]
    tab = {"in_arg": [members[l][0][i][0] for l in range(L) for i in range(ni)],
           "in_nz": [members[l][0][i][1] for l in range(L) for i in range(ni)],
           "out_res": [members[l][2][k][0] for l in range(L) for k in range(m)],
           "out_nz": [members[l][2][k][1] for l in range(L) for k in range(m)]}
    parts = [_template(name, prog, first, slots),
             f"static const double {name}_c[{L * no}] = {{{', '.join(repr(v) for o in own for v in (o or [0.0]))}}};"]
    if L > 1:
        parts[0] = f"#ifndef ALPES_LANES\n{parts[0]}#endif"
    parts += [f"static const int {name}_{t}[{max(len(v), 1)}] = {{{', '.join(map(str, v)) or '0'}}};"
              for t, v in tab.items()]
    scalar = (f"  for (l = 0; l < {L}; ++l) {{\n"
              f"    for (i = 0; i < {ni}; ++i) w[i] = arg[{name}_in_arg[{ni} * l + i]][{name}_in_nz[{ni} * l + i]];\n"
              f"    {name}(w, w + {ni}, {name}_c + {no} * l);\n"
              f"    for (i = 0; i < {m}; ++i) res[{name}_out_res[{m} * l + i]][{name}_out_nz[{m} * l + i]] = "
              f"w[{ni} + i];\n  }}")
    if L == 1:
        return "\n".join(parts), scalar, ni + m
    parts += ["#ifdef ALPES_LANES", _lane_template(f"{name}_v", prog, first, slots), "#endif"]
    vector = (f"  for (l = 0; l < {L}; l += ALPES_VL) {{ /* ALPES_VL blocks at once, the spare lanes a copy of the "
              "first */\n"
              "    const double* cl[ALPES_VL];\n    int u;\n"
              "    for (u = 0; u < ALPES_VL; ++u) {\n"
              f"      const int b = l + u < {L} ? l + u : l;\n"
              f"      cl[u] = {name}_c + {no} * b;\n"
              f"      for (i = 0; i < {ni}; ++i) w[ALPES_VL * i + u] = arg[{name}_in_arg[{ni} * b + i]][{name}_in_nz[{ni} * b + i]];\n"
              "    }\n"
              f"    {name}_v(w, w + ALPES_VL * {ni}, cl);\n"
              f"    for (i = 0; i < {m}; ++i)\n      for (u = 0; u < ALPES_VL && l + u < {L}; ++u)\n"
              f"        res[{name}_out_res[{m} * (l + u) + i]][{name}_out_nz[{m} * (l + u) + i]] = "
              f"w[ALPES_VL * ({ni} + i) + u];\n  }}")
    return "\n".join(parts), f"#ifdef ALPES_LANES\n{vector}\n#else\n{scalar}\n#endif", (ni + m) * 4
