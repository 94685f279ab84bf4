"""Python values of a case's dict that JSON does not know, for ``Case.from_dict``."""

import os


def json_value(value):
    """``json.dumps``'s ``default``: a NumPy scalar (``np.int64``, ``np.float32``, ``np.bool_``)
    or array (a 0-d array is a number) as the Python number or list it holds, a path object as
    its string. Anything else raises ``TypeError``, which ``from_dict`` reports."""
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        return value.tolist()
    return os.fspath(value)
