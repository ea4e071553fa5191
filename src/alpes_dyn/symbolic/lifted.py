"""An expression's numeric constants as an input: code keyed on a model's structure, not on its values.

The symbolic dynamics are built from numbers -- masses, inertias, lengths, springs, friction, rotor inertia,
transmission ratios -- that CasADi stores in the expression graph as constants, and so in the generated C as
literals: the compile cache (:mod:`alpes_dyn.simulation.buildcache`, keyed on the C source) then compiles again
whenever a value changes (each identified file, each draw of a sweep). :func:`lift_constants` rewrites a function
``f(x_1, ..., x_k)`` as ``f_p(x_1, ..., x_k, p)`` whose constants are the entries of the new input ``p``, and gives
``p``'s values: ``f_p(..., values)`` computes what ``f`` computes, the same operations in the same order (to the last
bit: a constant read from ``p`` is the same double as the literal).

One entry of ``p`` per *use* of a constant (per operand of an operation that reads it), not per constant: CasADi
stores one node per distinct value, so on a nominal finger whose three springs are equal one node feeds three
products, on an identified one three nodes do; per use, both give the same ``f_p`` (the same operations, the same
graph), hence the same generated C and one compiled library. What still changes the graph -- an effect present or
not, a value of exactly 0 or 1 that CasADi simplified away when it built the expression, another URDF or
transmission -- changes the code, as it should: that is the model's structure.

Lift an expression *before* ``cse`` merges its common subexpressions: ``cse`` merges two products of a variable by
the same constant node, which per-use lifting then cannot separate again.
"""

from __future__ import annotations

import casadi as cs
import numpy as np

from ..errors import ModelError

__all__ = ["lift_constants"]


def lift_constants(f: cs.Function, name: str | None = None) -> tuple[cs.Function, np.ndarray]:
    """``(f_p, values)``: ``f_p(*inputs, p)`` is ``f`` with its constants read from ``p`` (``values``, (np,)).

    Parameters
    ----------
    f : casadi.Function
        An SX function (``cs.Function`` of ``cs.SX`` symbols), any number of inputs and outputs.
    name : str or None, optional
        The name of ``f_p`` (default None: ``f``'s).

    Returns
    -------
    f_p : casadi.Function
        ``f``'s inputs, then ``p`` (np,); ``f``'s outputs, same sparsity.
    values : numpy.ndarray, shape (np,)
        The constants, one per use in ``f``'s algorithm (module doc), in its order.

    Raises
    ------
    ModelError
        ``f`` not an SX function.

    Notes
    -----
    The replay is one Python step per instruction of ``f`` (a finger's right-hand side, a few thousand instructions,
    in a fraction of a second); lift the model's right-hand side, not a filter step built from it.
    """
    if not isinstance(f, cs.Function) or not f.is_a("SXFunction"):
        raise ModelError(f"lift_constants: expected an SX casadi.Function, got {type(f).__name__}")
    ins = f.sx_in()
    elems = [[x.nz[j] for j in range(x.nnz())] for x in ins]
    outs = [[cs.SX(0)] * f.nnz_out(i) for i in range(f.n_out())]
    slots: dict[int, object] = {}  # work slot -> SX element, or a float: a constant not yet used
    values: list[float] = []
    p_elems: list[cs.SX] = []

    def read(slot: int) -> cs.SX:
        v = slots[slot]
        if isinstance(v, float):  # a use of a constant: an entry of p of its own
            s = cs.SX.sym(f"p_{len(values)}")
            values.append(v)
            p_elems.append(s)
            return s
        return v  # type: ignore[return-value]

    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        i_in, i_out = f.instruction_input(k), f.instruction_output(k)
        if op == cs.OP_CONST:
            slots[i_out[0]] = float(f.instruction_constant(k))
        elif op == cs.OP_INPUT:
            slots[i_out[0]] = elems[i_in[0]][i_in[1]]
        elif op == cs.OP_OUTPUT:
            outs[i_out[0]][i_out[1]] = read(i_in[0])
        elif len(i_in) == 1:
            slots[i_out[0]] = cs.SX.unary(op, read(i_in[0]))
        elif len(i_in) == 2:
            slots[i_out[0]] = cs.SX.binary(op, read(i_in[0]), read(i_in[1]))
        else:  # free parameters, calls: not in the expressions lifted here
            raise ModelError(f"lift_constants: instruction {k} of {f.name()} (operation {op}) is not a plain "
                             "unary or binary operation")
    p = cs.vertcat(*p_elems) if p_elems else cs.SX(0, 1)
    res = [cs.SX(f.sparsity_out(i), cs.vertcat(*o) if o else cs.SX(0, 1)) for i, o in enumerate(outs)]
    f_p = cs.Function(name or f.name(), [*ins, p], res, [*f.name_in(), "p"], list(f.name_out()))
    return f_p, np.array(values, dtype=float)
