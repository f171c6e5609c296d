"""Machine-ready firing data: nozzle order, packing into 32-bit words, TIFF planes."""

from .packing import (BITS_CHOICES, WORD_BYTE_ORDER, bits_for_levels, nozzle_order, pack_levels, packed_bytes,
                      read_packed, tiff_bytes, unpack_levels, words_per_row)

__all__ = ["BITS_CHOICES", "WORD_BYTE_ORDER", "bits_for_levels", "nozzle_order", "pack_levels", "packed_bytes", "read_packed",
           "tiff_bytes", "unpack_levels", "words_per_row"]
