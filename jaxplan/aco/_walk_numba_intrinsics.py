"""Scalar and vector pieces of the native ant walk (numba), each the exact float32 counterpart of a `jaxplan.aco._walk`
array operation: the counter-based uniform, XLA's exp, a fused multiply-add, and an LLVM vector intrinsic
for the 8-connected walk's tabu test and draw of 16 ants at once (`jaxplan.aco._walk_numba_kernels`).

The functions here are inlined into the kernels that use them and are not cached on their own: numba's
cache of a function does not notice changes in another file's functions it calls (numba issue #1833), so
only the FFI handlers are cached, keyed on this file too (`jaxplan.aco._walk_ffi`).
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

__all__ = ["TINY", "LANES", "fma32", "uniform", "move_between", "exp_xla", "u2f", "tabu_draw_lanes"]

_F = np.float32
TINY = np.finfo(np.float32).tiny  # as `walk`: keeps allowed moves drawable when their weights underflowed
_M32 = np.uint64(0xFFFFFFFF)
_H1, _H2, _H3, _H4 = np.uint64(0x9E3779B9), np.uint64(0x85EBCA6B), np.uint64(0x7FEB352D), np.uint64(0x846CA68B)
_S8, _S15, _S16 = np.uint64(8), np.uint64(15), np.uint64(16)
_INV24 = np.float32(1.0 / (1 << 24))


@intrinsic
def fma32(typingctx, a, b, c):
    """float32 fused multiply-add (one rounding), as LLVM emits it for XLA's contracted a*b + c."""
    sig = types.float32(types.float32, types.float32, types.float32)

    def codegen(context, builder, signature, args):
        f = ir.FloatType()
        fn = builder.module.declare_intrinsic("llvm.fma", [f], fnty=ir.FunctionType(f, [f, f, f]))
        return builder.call(fn, args)

    return sig, codegen


@njit(nogil=True, inline="always")
def uniform(seed, t, ant):
    """`hash_uniform` for one (seed, step, ant): lowbias32, in uint64 arithmetic masked to 32 bits."""
    x = ((np.uint64(ant) * _H1) & _M32) ^ ((np.uint64(t) * _H2 + np.uint64(seed)) & _M32)
    x = x ^ (x >> _S16)
    x = (x * _H3) & _M32
    x = x ^ (x >> _S15)
    x = (x * _H4) & _M32
    x = x ^ (x >> _S16)
    return np.float32(x >> _S8) * _INV24


@njit(nogil=True, inline="always")
def move_between(a, b, width, lut):
    """`moves_between` for two flat cells: the move index from ``a`` to ``b``, −1 if none."""
    dx = b % width - a % width
    dy = b // width - a // width
    if abs(dx) > 2 or abs(dy) > 2:
        return -1
    return lut[(dy + 2) * 5 + dx + 2]


@njit(nogil=True, inline="always")
def exp_xla(x):
    """float32 e^x exactly as XLA's CPU backend (jaxlib 0.10) computes it.

    Only the hook path needs an exponential inside the step, and libm's expf differs from
    XLA's in the last bit for about 1 % of arguments, which would change a few draws. XLA
    emits Cephes' polynomial (``xla/backends/cpu/codegen/polynomial_approximations.cc``) and
    LLVM contracts every multiply-add into an FMA; results below 2^-126 are flushed to zero
    (XLA runs with FTZ). ``tests/test_walk_numba.py`` checks this against `jnp.exp`.
    """
    x = min(max(x, _F(-87.8)), _F(88.8))
    n = np.float32(np.floor(fma32(x, _F(1.44269504088896341), _F(0.5))))
    n = min(max(n, _F(-127.0)), _F(127.0))
    r = fma32(-_F(0.693359375), n, x)
    r = fma32(-_F(-2.12194440e-4), n, r)
    z = fma32(r, _F(1.9875691500e-4), _F(1.3981999507e-3))
    z = fma32(z, r, _F(8.3334519073e-3))
    z = fma32(z, r, _F(4.1665795894e-2))
    z = fma32(z, r, _F(1.6666665459e-1))
    z = fma32(z, r, _F(5.0000001201e-1))
    z = fma32(z, r * r, r)
    z = _F(1.0) + z
    # 2^n from its biased exponent: 0.0 for n = -127.
    e = z * u2f(np.uint32((np.int32(n) + 127) << 23))
    return e if not e < TINY else _F(0.0)


@intrinsic
def u2f(typingctx, x):
    """float32 with the given uint32 bit pattern."""
    sig = types.float32(types.uint32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.FloatType())

    return sig, codegen


_I32 = ir.IntType(32)


def _splat(builder, value, vtype):
    """A vector of ``vtype`` with every lane ``value``."""
    v = builder.insert_element(ir.Constant(vtype, None), value, ir.Constant(_I32, 0))
    return builder.shuffle_vector(v, ir.Constant(vtype, None), ir.Constant(ir.VectorType(_I32, vtype.count),
                                                                             [0] * vtype.count))


_I64 = ir.IntType(64)
LANES = 16
"""Ants the 8-connected walk steps at once, one per SIMD lane (`tabu_draw_lanes`): 16 float32 lanes fill
an AVX-512 register; with narrower vectors LLVM splits them (same results)."""


def _gather(builder, base, index, scale, etype):
    """``<LANES x etype>`` loaded from the addresses ``base + index * scale`` (an int64 address and an int64
    index vector): one vector gather instead of a load per lane."""
    iv = ir.VectorType(_I64, LANES)
    addresses = builder.add(builder.mul(index, ir.Constant(iv, [scale] * LANES)), _splat(builder, base, iv))
    pv = ir.VectorType(etype.as_pointer(), LANES)
    vt = ir.VectorType(etype, LANES)
    name = f"llvm.masked.gather.v{LANES}{'f32' if isinstance(etype, ir.FloatType) else 'i32'}.v{LANES}p0"
    fn = builder.module.globals.get(name) or ir.Function(
        builder.module, ir.FunctionType(vt, [pv, _I32, ir.VectorType(ir.IntType(1), LANES), vt]), name=name)
    return builder.call(fn, [builder.inttoptr(addresses, pv), ir.Constant(_I32, 4),
                             ir.Constant(ir.VectorType(ir.IntType(1), LANES), [1] * LANES), ir.Constant(vt, None)])


@intrinsic
def tabu_draw_lanes(typingctx, table, seen, vbits, offp, pp, stamp, row, pos, u, k_out, total_out):
    """`draw` for `LANES` ants at once on an 8-connected grid, each in its own SIMD lane.

    Lane l's ant stands on cell ``pos[l]`` (``pp[l]`` on the padded tabu grid ``seen``, ``row[l]`` in
    ``table``); move j is allowed when bit j of ``vbits[pos]`` is set and ``seen[pp + offp[j]] != stamp[l]``.
    Writes ``total_out[l]``, the float32 sum of the weights ``table[row, j] + TINY`` of the allowed moves
    (0 for the others) left to right, and ``k_out[l]``, the number of the first seven running sums at or
    below ``u[l] * total`` (counted as the sums not above it, which for non-decreasing sums is the index
    of the first one above it: `draw`'s). Each lane does the float32 operations of the one-ant step in
    the same order, so the draws are the same bits; the loads are vector gathers (one per move for the
    tabu and one per move for the weights, for all lanes), so the step's dependent loads and its chain of
    seven float additions are paid once per `LANES` ants.

    Args (all arrays C-contiguous): table ``f32[R, 8]``; seen ``i32[S]``; vbits ``i32[C]`` (allowed
    moves as bits); offp ``i64[8]``; pp, row, pos ``i64[LANES]``; stamp ``i32[LANES]``; u ``f32[LANES]``;
    k_out ``i64[LANES]``; total_out ``f32[LANES]``. Every lane's indices must be valid (an idle lane
    points at any valid cell).
    """
    sig = types.void(table, seen, vbits, offp, pp, stamp, row, pos, u, k_out, total_out)

    def codegen(context, builder, signature, args):
        data = [context.make_array(t)(context, builder, a).data for t, a in zip(signature.args, args, strict=True)]
        base = [builder.ptrtoint(d, _I64) for d in data]
        f32 = ir.FloatType()
        iv, i32v, fv = ir.VectorType(_I64, LANES), ir.VectorType(_I32, LANES), ir.VectorType(f32, LANES)

        def load(i, vt):
            return builder.load(builder.bitcast(data[i], vt.as_pointer()), align=4)

        ppv, stv, rowv, posv, uv = load(4, iv), load(5, i32v), load(6, iv), load(7, iv), load(8, fv)
        visited = ir.Constant(i32v, [0] * LANES)
        for j in range(8):
            offj = builder.load(builder.gep(data[3], [ir.Constant(_I64, j)]))
            stamps = _gather(builder, base[1], builder.add(ppv, _splat(builder, offj, iv)), 4, _I32)
            hit = builder.zext(builder.icmp_signed("==", stamps, stv), i32v)
            visited = builder.or_(visited, builder.shl(hit, ir.Constant(i32v, [j] * LANES)))
        allowed = builder.and_(_gather(builder, base[2], posv, 4, _I32),
                               builder.xor(visited, ir.Constant(i32v, [-1] * LANES)))
        first = builder.mul(rowv, ir.Constant(iv, [8] * LANES))
        sums = []
        acc = None
        for j in range(8):
            w = _gather(builder, base[0], builder.add(first, ir.Constant(iv, [j] * LANES)), 4, f32)
            w = builder.fadd(w, ir.Constant(fv, [float(TINY)] * LANES))
            on = builder.icmp_unsigned("!=", builder.and_(allowed, ir.Constant(i32v, [1 << j] * LANES)),
                                       ir.Constant(i32v, [0] * LANES))
            w = builder.select(on, w, ir.Constant(fv, [0.0] * LANES))
            acc = w if acc is None else builder.fadd(acc, w)  # 0 + w0 is w0 exactly: start from w0
            sums.append(acc)
        threshold = builder.fmul(uv, acc)
        k = ir.Constant(iv, [0] * LANES)
        for j in range(7):
            k = builder.add(k, builder.zext(builder.not_(builder.fcmp_ordered(">", sums[j], threshold)), iv))
        builder.store(k, builder.bitcast(data[9], iv.as_pointer()), align=8)
        builder.store(acc, builder.bitcast(data[10], fv.as_pointer()), align=4)
        return context.get_dummy_value()

    return sig, codegen
