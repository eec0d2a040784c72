"""pytest plugin loaded only by the mutation run ([tool.mutmut] pytest_add_cli_args, docs/mutation.md).

mutmut routes every call of a mutated function through a trampoline, which adds stack frames: the
assembler's deepest legal expression (MAX_EXPR_DEPTH levels, tests/lang/test_assembler.py) would
then hit Python's default recursion limit of 1000 before the assembler's own limit is reached.
"""
import sys

sys.setrecursionlimit(max(sys.getrecursionlimit(), 20_000))
