"""Faster first compiles: two measures in numba's compiler that change how it works, not
what the kernels compute.  Each is installed on numba 0.68.1 only, the pinned version
whose code it was checked against.  ``MKCOLLISION_PLAIN_NUMBA=1`` leaves numba as it is,
and a comma list of ``ssa``, ``flags`` leaves out those measures (for comparisons;
``tests/test_jit.py`` compiles with and without).  Found with cProfile over the whole
one-process compile (``compile_progress.warm_up_all(jobs=1)``), where numba's Python
passes take about half the time and LLVM the rest.

- SSA over the blocks that name a variable (``_ssa_rewrite_where_named``).  numba's SSA
  reconstruction (numba.core.ssa) fixes one variable at a time, and for each it rebuilds
  every block of the function twice, calling a handler on every statement: a function
  with thousands of blocks and thousands of variables assigned twice costs millions of
  handler calls.  Both rewrites change only the statements that name the variable (a
  definition renamed, a use pointed at its reaching definition); every other block
  comes out as a copy of itself.  So the blocks
  where each variable is named are listed once, before the first variable is fixed, and
  the two rewrites visit those blocks and copy the others' statement lists.  Fixing one
  variable never changes where another is named (its new names are fresh, the copies of
  rewritten statements keep their other variables, and the phi nodes it adds name only
  its own versions), so the list stays true through the whole pass.  The same
  statements come out in the same order, the same fresh names are made in the same
  order, and the LLVM IR is the same text (tests/test_jit.py).
- Flag comparisons without properties (``_quick_flag_comparisons``).  numba keys the
  implementations of every ``@overload`` it types by the compile's flags (a
  TargetConfig), whose ``__hash__`` and ``__eq__`` build a dict of all ~30 options
  through their properties: half a million times in a cold compile.  The hash is
  that of the sorted option names (numba's own expression, which iterates the dict's
  keys), the same for every instance of a class, so it is computed once a class; the
  values are read from the instance's dict with the defaults taken once a class; and an
  object equals itself without reading them.  Same results, about 25 times fewer
  Python calls.
"""
import os
import threading

import numba

_PLAIN = {w.strip() for w in os.environ.get("MKCOLLISION_PLAIN_NUMBA", "").split(",")}


def _wanted(measure):
    return "1" not in _PLAIN and measure not in _PLAIN


class _Where(threading.local):
    """The blocks that name each variable, for the SSA pass running on this thread
    (numba compiles under one lock, but a nested pass may start inside another)."""

    def __init__(self):
        self.stack = []


_WHERE = _Where()
_PLAIN_SSA_RUN = None        # numba's own _run_ssa, once the SSA measure is installed


def _ssa_rewrite_where_named():
    """Install the SSA measure (module docstring); returns whether it is installed."""
    try:
        from numba.core import ir, ssa
        plain_run = ssa._run_ssa
        plain_rewrite = ssa._run_block_rewrite
    except (ImportError, AttributeError):
        return False
    if getattr(plain_run, "_where_named", False):
        return True

    def named_in(blocks):
        where = {}
        for label, blk in blocks.items():
            for stmt in blk.body:
                for var in stmt.list_vars():
                    where.setdefault(var.name, set()).add(label)
        return where

    def _run_ssa(blocks):
        _WHERE.stack.append(named_in(blocks) if blocks else {})
        try:
            return plain_run(blocks)
        finally:
            _WHERE.stack.pop()

    def _run_block_rewrite(blocks, states, handler):
        if not _WHERE.stack or "varname" not in states:
            return plain_rewrite(blocks, states, handler)
        named = _WHERE.stack[-1].get(states["varname"], ())
        newblocks = {}
        for label, blk in blocks.items():
            if label in named:
                newblocks.update(plain_rewrite({label: blk}, states, handler))
            else:
                newblk = ir.Block(scope=blk.scope, loc=blk.loc)
                newblk.body = list(blk.body)
                newblocks[label] = newblk
        return newblocks

    global _PLAIN_SSA_RUN
    _PLAIN_SSA_RUN = plain_run
    _run_ssa._where_named = True
    _run_ssa.__doc__ = plain_run.__doc__
    ssa._run_ssa = _run_ssa
    ssa._run_block_rewrite = _run_block_rewrite
    return True


def _quick_flag_comparisons():
    """Install the flag measure (module docstring); returns whether it is installed."""
    try:
        from numba.core import targetconfig
        cls = targetconfig.TargetConfig
        plain_eq = cls.__eq__
    except (ImportError, AttributeError):
        return False
    if getattr(plain_eq, "_quick", False):
        return True
    defaults, hashes = {}, {}

    def class_defaults(klass):
        got = defaults.get(klass)
        if got is None:
            got = defaults[klass] = tuple((k, o.default) for k, o in klass.options.items())
        return got

    def values(self):
        own = self._values
        return {k: (own[k] if k in own else d) for k, d in class_defaults(type(self))}

    def __hash__(self):
        klass = type(self)
        got = hashes.get(klass)
        if got is None:
            got = hashes[klass] = hash(tuple(sorted(klass.options)))
        return got

    def __eq__(self, other):
        if self is other:
            return True
        if isinstance(other, cls):
            return values(self) == values(other)
        return NotImplemented

    __eq__._quick = True
    for name, fn in (("values", values), ("__hash__", __hash__), ("__eq__", __eq__)):
        fn.__doc__ = getattr(cls, name).__doc__
        setattr(cls, name, fn)
    return True


_ACTIVE = not numba.config.DISABLE_JIT and numba.__version__ == "0.68.1"
SSA_WHERE_NAMED = _ACTIVE and _wanted("ssa") and _ssa_rewrite_where_named()
QUICK_FLAG_COMPARISONS = _ACTIVE and _wanted("flags") and _quick_flag_comparisons()
