"""array.array <-> numpy helpers shared by the adapters."""
import array

import numpy as np


def view(field, dtype=np.float64):
    """Zero-copy, read-only numpy view of an ``array.array`` message field."""
    out = np.frombuffer(field, dtype=dtype) if len(field) else np.zeros(0, dtype)
    out.flags.writeable = False
    return out


def pack(values, typecode, dtype):
    """One ``array.array`` holding ``values`` flattened, converted to ``dtype``."""
    arr = array.array(typecode)
    arr.frombytes(np.ascontiguousarray(values, dtype=dtype).tobytes())
    return arr
