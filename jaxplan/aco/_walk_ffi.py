"""The XLA FFI handlers of the native walk and update: XLA calls them with its own buffers, so nothing is
copied or allocated per call and no Python runs (a `jax.pure_callback` would cost more than the whole walk
of a small colony). The call frame is read with the offsets of XLA's FFI C API
(``xla/ffi/api/c_api.h``, API version 0.x, x86-64/aarch64 layout).

The handlers are numba `cfunc`s, compiled once per process or loaded from numba's on-disk cache. They are
the only cached native code of the walk: a cached function holds the code of every function it calls,
but numba checks only the caller's own file for changes (numba issue #1833). So each handler closes over
a hash of the source of every module whose code it compiles in (`_NATIVE_MODULES`), and numba's cache key
includes a function's closure: an edit anywhere in the native walk recompiles the handlers.
"""

from __future__ import annotations

import hashlib
from importlib import resources

import jax
import numba
import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from jaxplan.aco._walk_numba_kernels import loop_counters, walk_all
from jaxplan.aco._walk_numba_update import N_STATS, deposit_paths, penalise, stats_all
from jaxplan.core.compile_cache import compile_notice, on_first_use

__all__ = ["register", "source_fingerprint"]


def _pointer(nbtype):
    """An intrinsic turning an int64 address into a ``CPointer(nbtype)`` (for `numba.carray`)."""

    @intrinsic
    def ptr(typingctx, addr):
        sig = types.CPointer(nbtype)(types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(types.CPointer(nbtype)))

        return sig, codegen

    return ptr


_I64P, _I32P, _U32P, _F32P, _I8P, _U8P = (_pointer(t) for t in (types.int64, types.int32, types.uint32, types.float32,
                                                                  types.int8, types.uint8))


@intrinsic
def _address(typingctx, p):
    """int64 address of a void pointer."""
    sig = types.int64(types.voidptr)

    def codegen(context, builder, signature, args):
        return builder.ptrtoint(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _null(typingctx):
    """The null void pointer (an FFI handler's "no error")."""
    sig = types.voidptr()

    def codegen(context, builder, signature, args):
        return context.get_constant_null(types.voidptr)

    return sig, codegen


@njit(nogil=True, inline="always")
def _i64(addr):
    return numba.carray(_I64P(addr), (1,))[0]


@njit(nogil=True, inline="always")
def _i32(addr):
    return numba.carray(_I32P(addr), (1,))[0]


@njit(nogil=True, inline="always")
def _data(lst, i):
    """Data address of the i-th `XLA_FFI_Buffer*` of an args/rets list."""
    return _i64(_i64(lst + 8 * i) + 24)


@njit(nogil=True, inline="always")
def _dim(lst, i, axis):
    """Size of axis ``axis`` of the i-th buffer of an args/rets list."""
    return _i64(_i64(_i64(lst + 8 * i) + 40) + 8 * axis)


@njit(nogil=True, inline="always")
def _not_execute(base):
    """Answers XLA's metadata query (FFI API version 0.1, no traits, stateless); True unless this
    call is the EXECUTE stage, the only one with work."""
    ext = _i64(base + 8)
    if ext != 0 and _i32(ext + 8) == 1:
        # XLA asks for the handler's metadata (XLA_FFI_Metadata_Extension). Older minor versions
        # are accepted by every newer XLA.
        meta = _i64(ext + 24)
        m64 = numba.carray(_I64P(meta), (6,))
        m32 = numba.carray(_I32P(meta), (12,))
        m64[1] = 24  # api_version.struct_size
        m64[2] = 0  # api_version.extension_start
        m32[6] = 0  # major
        m32[7] = 1  # minor
        m32[8] = 0  # traits
        m64[5] = 0  # state_type_id: XLA_FFI_UNKNOWN_TYPE_ID
        return True
    return _i32(base + 32) != 3


@njit(nogil=True, inline="always")
def _lists(frame):
    """``(args, rets)``: the addresses of the call frame's argument and result buffer lists; ``(0, 0)`` when the
    call is not the EXECUTE stage (`_not_execute` has answered it), and the handler returns at once."""
    base = _address(frame)
    if _not_execute(base):
        return np.int64(0), np.int64(0)
    return _i64(base + 40 + 32), _i64(base + 80 + 32)


@njit(nogil=True)
def _walk_call(frame):
    """``XLA_FFI_Error* handler(XLA_FFI_CallFrame*)`` for `jaxplan.aco._walk_numba.walk`'s call; see `walk` for
    the buffers."""
    args, rets = _lists(frame)
    if args == 0:
        return _null()
    C, K = _dim(args, 0, 0), _dim(args, 0, 1)
    A = _dim(args, 5, 1)
    nbr = numba.carray(_I32P(_data(args, 0)), (C, K))
    table = numba.carray(_F32P(_data(args, 1)), (_dim(args, 1, 0), K))
    hook_l = numba.carray(_F32P(_data(args, 2)), (_dim(args, 2, 0), _dim(args, 2, 1), K))
    right_turn = numba.carray(_I32P(_data(args, 3)), (K,))
    turn_rule = numba.carray(_U8P(_data(args, 4)), (_dim(args, 4, 0),))
    ints = numba.carray(_I32P(_data(args, 5)), (5, A))
    seed = numba.carray(_U32P(_data(args, 6)), (A,))
    lut = numba.carray(_I32P(_data(args, 7)), (25,))
    alert = numba.carray(_U8P(_data(args, 8)), (_dim(args, 8, 0),))
    cfg = numba.carray(_I32P(_data(args, 9)), (6,))
    L = np.int64(cfg[0])
    movef = numba.carray(_F32P(_data(args, 10)), (K + K * K,))
    cellf = numba.carray(_F32P(_data(args, 11)), (3, _dim(args, 11, 1)))
    vbits = numba.carray(_U8P(_data(args, 12)), (_dim(args, 12, 0),))
    hook_v = numba.carray(_I32P(_data(args, 13)), (_dim(args, 13, 0),))
    cells = numba.carray(_I32P(_data(rets, 0)), (A, L + 1))
    moves = numba.carray(_I8P(_data(rets, 1)), (A, L))
    per_ant = numba.carray(_I32P(_data(rets, 2)), (3, A))
    counters = numba.carray(_I32P(_data(rets, 3)), (2,))
    penalty = numba.carray(_F32P(_data(rets, 4)), (_dim(rets, 4, 0),))
    marks = numba.carray(_U8P(_data(rets, 5)), (_dim(rets, 5, 0),))
    stats = numba.carray(_F32P(_data(rets, 6)), (N_STATS, A))
    walk_all(nbr, table, hook_l, hook_v, right_turn, turn_rule, ints[0], ints[1], ints[2], ints[3], seed, ints[4],
             alert, vbits, L, np.int64(cfg[1]), lut, np.int64(cfg[2]), np.int64(cfg[3]), cfg[4] != 0,
             np.int64(cfg[5]), movef,
             cellf, cells, moves, per_ant[0], per_ant[1], per_ant[2], penalty, marks, stats)
    loop_counters(per_ant[2], L, counters)
    return _null()


@njit(nogil=True)
def _stats_call(frame):
    """The handler of `jaxplan.aco._walk_numba.path_stats`: cells ``i32[A, L + 1]``, moves ``i8[A, L]``,
    n ``i32[A]``, movef, cellf, ``i32[1]`` parallel chunks -> stats ``f32[N_STATS, A]``."""
    args, rets = _lists(frame)
    if args == 0:
        return _null()
    A, L1 = _dim(args, 0, 0), _dim(args, 0, 1)
    nf = _dim(args, 3, 0)
    K = np.int64(0)
    while K + K * K < nf:
        K += 1
    cells = numba.carray(_I32P(_data(args, 0)), (A, L1))
    moves = numba.carray(_I8P(_data(args, 1)), (A, L1 - 1))
    n = numba.carray(_I32P(_data(args, 2)), (A,))
    movef = numba.carray(_F32P(_data(args, 3)), (nf,))
    cellf = numba.carray(_F32P(_data(args, 4)), (3, _dim(args, 4, 1)))
    n_chunks = np.int64(numba.carray(_I32P(_data(args, 5)), (1,))[0])
    stats = numba.carray(_F32P(_data(rets, 0)), (N_STATS, A))
    stats_all(cells, moves, n, movef, cellf, K, n_chunks, stats)
    return _null()


@njit(nogil=True)
def _deposit_call(frame):
    """The handler of `jaxplan.aco._walk_numba.deposit`: tau ``f32[T]`` (aliased to the result), then for the
    ants and for the best-so-far paths each: cells ``i32[P, L + 1]``, moves ``i8[P, L]``, n ``i32[P]``, amounts
    ``f32[2, P]``, colonies ``i32[2, P]``; then ``i32[2]`` (C·K, K), the retreat counts ``f32[T]`` (or ``[1]``:
    none) and ``f32[1]`` the factor an edge keeps per retreat."""
    args, rets = _lists(frame)
    if args == 0:
        return _null()
    tau = numba.carray(_F32P(_data(rets, 0)), (_dim(rets, 0, 0),))
    sizes = numba.carray(_I32P(_data(args, 11)), (2,))
    CK = np.int64(sizes[0])
    K = np.int64(sizes[1])
    # Own-colony deposits of the ants, their deposits into the next colony, then the best-so-far
    # paths' (own, next): the order `jaxplan.aco._colony._deposit_jax` adds them in.
    for group in range(2):
        first = 1 + 5 * group
        P, L1 = _dim(args, first, 0), _dim(args, first, 1)
        cells = numba.carray(_I32P(_data(args, first)), (P, L1))
        moves = numba.carray(_I8P(_data(args, first + 1)), (P, L1 - 1))
        n = numba.carray(_I32P(_data(args, first + 2)), (P,))
        amounts = numba.carray(_F32P(_data(args, first + 3)), (2, P))
        colonies = numba.carray(_I32P(_data(args, first + 4)), (2, P))
        for kind in range(2):
            deposit_paths(tau, cells, moves, n, amounts[kind], colonies[kind], CK, K)
    penalty = numba.carray(_F32P(_data(args, 12)), (_dim(args, 12, 0),))
    keep = numba.carray(_F32P(_data(args, 13)), (1,))
    if penalty.shape[0] == tau.shape[0]:
        penalise(tau, penalty, keep[0])
    return _null()


# Every module whose code the handlers compile in (`jaxplan.aco._walk` for its status codes).
_NATIVE_MODULES = ("_walk.py", "_walk_numba_intrinsics.py", "_walk_numba_update.py", "_walk_numba_kernels.py",
                   "_walk_ffi.py")


def source_fingerprint() -> int:
    """A hash of the source of `_NATIVE_MODULES`, as a non-negative int64: part of the handlers' cache key."""
    h = hashlib.sha256()
    package = resources.files("jaxplan.aco")
    for name in _NATIVE_MODULES:
        h.update(package.joinpath(name).read_bytes())
    return int.from_bytes(h.digest()[:8], "little") >> 1


def _handlers(fingerprint: int) -> dict:
    """The FFI targets' handlers, each closing over ``fingerprint``: numba's cache key of a function includes
    its closure's values, so the cached handlers are those compiled from the current native sources."""

    def walk(frame):
        fingerprint  # noqa: B018 (a closure value: in numba's cache key)
        return _walk_call(frame)

    def stats(frame):
        fingerprint  # noqa: B018
        return _stats_call(frame)

    def deposit(frame):
        fingerprint  # noqa: B018
        return _deposit_call(frame)

    return {"jaxplan_aco_walk": walk, "jaxplan_aco_path_stats": stats, "jaxplan_aco_deposit": deposit}


_HANDLERS: dict = {}  # the compiled cfuncs, kept alive while XLA may call them


def register() -> None:
    """Compiles (or loads from numba's cache) the handlers and registers them with XLA, once."""
    if not _HANDLERS:
        on_first_use()  # the cache folder is fixed when a cfunc is made
        # Start numba's thread pool first: loading a cached handler links the parallel kernels
        # against the pool's launch functions, which are null until then.
        numba.get_num_threads()
        with compile_notice("the IACO walk", 30):  # ~30 s on 2 cores when not cached; a cached load ~0.3 s
            for target, fn in _handlers(source_fingerprint()).items():
                handler = numba.cfunc(types.voidptr(types.voidptr), cache=True, nopython=True)(fn)  # type: ignore[call-arg]
                jax.ffi.register_ffi_target(target, jax.ffi.pycapsule(handler.ctypes), platform="cpu")
                _HANDLERS[target] = handler
