"""TMCL assembler, disassembler, binary program files and bundled include files."""
from .assembler import AsmError, Program, assemble, assemble_file
from .binfile import BinFileError, Instruction
from .disassembler import disassemble

__all__ = ["AsmError", "BinFileError", "Instruction", "Program", "assemble", "assemble_file", "disassemble"]
