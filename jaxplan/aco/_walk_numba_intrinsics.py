"""Scalar pieces of the native ant walk (numba), each the exact float32 counterpart of a `jaxplan.aco._walk`
array operation: the counter-based uniform, XLA's exp, a fused multiply-add, and two LLVM vector intrinsics
for the 8-connected walk's tabu test and draw (`jaxplan.aco._walk_numba_kernels`).

The functions here are inlined into the kernels that use them and are not cached on their own: numba's
cache of a function does not notice changes in another file's functions it calls (numba issue #1833), so
only the FFI handlers are cached, keyed on this file too (`jaxplan.aco._walk_ffi`).
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

__all__ = ["TINY", "fma32", "uniform", "move_between", "exp_xla", "u2f", "visited3x3", "draw8"]

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


@intrinsic
def visited3x3(typingctx, seen, i, row, stamp):
    """``uint32``: bit ``3 * r + c`` set where ``seen[i + r * row + c] == stamp`` (r, c in 0..2): the 3x3
    block of a padded tabu grid whose top-left is ``i``, each of its rows read as one 4-lane vector
    compare (the 4th lane is ignored; the grid needs one slot of slack at its end)."""
    sig = types.uint32(seen, types.int64, types.int64, types.int32)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        vt = ir.VectorType(_I32, 4)
        target = _splat(builder, args[3], vt)
        out = ir.Constant(_I32, 0)
        for r in range(3):
            ptr = builder.gep(data, [builder.add(args[1], builder.mul(args[2], ir.Constant(ir.IntType(64), r)))])
            hit = builder.icmp_signed("==", builder.load(builder.bitcast(ptr, vt.as_pointer()), align=4), target)
            bits = builder.and_(builder.zext(builder.bitcast(hit, ir.IntType(4)), _I32), ir.Constant(_I32, 7))
            out = builder.or_(out, builder.shl(bits, ir.Constant(_I32, 3 * r)))
        return out

    return sig, codegen


@intrinsic
def draw8(typingctx, table, row, allowed, u):
    """``(k, total)``, `draw` for one ant on an 8-connected grid: the weights ``table[row, j] + TINY`` of
    the moves j whose bit is set in ``allowed`` (0 for the others) summed left to right in float32
    (``total`` is the last running sum) and ``k`` the number of the first seven running sums at or
    below ``u * total``, found as the first one above it (the sums never decrease) with one vector
    compare. Same bits as the scalar loops of `walk_ant`."""
    sig = types.Tuple((types.int64, types.float32))(table, types.int64, types.uint32, types.float32)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        f32 = ir.FloatType()
        vt, it = ir.VectorType(f32, 8), ir.VectorType(_I32, 8)
        ptr = builder.gep(data, [builder.mul(args[1], ir.Constant(ir.IntType(64), 8))])
        w = builder.fadd(builder.load(builder.bitcast(ptr, vt.as_pointer()), align=4),
                         ir.Constant(vt, [float(TINY)] * 8))
        on = builder.icmp_unsigned("!=", builder.and_(_splat(builder, args[2], it),
                                                      ir.Constant(it, [1 << j for j in range(8)])),
                                   ir.Constant(it, [0] * 8))
        w = builder.select(on, w, ir.Constant(vt, [0.0] * 8))
        acc = builder.extract_element(w, ir.Constant(_I32, 0))
        sums = builder.insert_element(ir.Constant(vt, None), acc, ir.Constant(_I32, 0))
        for j in range(1, 8):
            acc = builder.fadd(acc, builder.extract_element(w, ir.Constant(_I32, j)))
            sums = builder.insert_element(sums, acc, ir.Constant(_I32, j))
        above = builder.fcmp_ordered(">", sums, _splat(builder, builder.fmul(args[3], acc), vt))
        first = builder.or_(builder.zext(builder.bitcast(above, ir.IntType(8)), _I32), ir.Constant(_I32, 0x80))
        cttz = builder.module.declare_intrinsic("llvm.cttz", [_I32], fnty=ir.FunctionType(_I32, [_I32, ir.IntType(1)]))
        k = builder.zext(builder.call(cttz, [first, ir.Constant(ir.IntType(1), 1)]), ir.IntType(64))
        return context.make_tuple(builder, signature.return_type, [k, acc])

    return sig, codegen
