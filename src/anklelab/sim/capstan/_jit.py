"""Compiler flags shared by the capstan kernels.

``FAST`` lets LLVM reassociate, contract and use approximate reciprocals and math functions, but
keeps NaN and infinity semantics (no ``nnan``/``ninf``): the safety checks depend on them.
"""

FAST = {"contract", "arcp", "reassoc", "afn"}
