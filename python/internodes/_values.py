"""A case's dict as the plain values JSON holds, for ``Case.from_dict``."""

import decimal
import math
import numbers
import os


def plain(value, key=""):
    """``value`` with every NumPy scalar or array (a 0-d array is a number) as the Python number
    or list it holds, every path object as its string, and every ``Fraction`` or ``Decimal`` as
    the nearest float. Raises ``ValueError`` naming the key (``body[0].youngs_modulus``) of a NaN
    or infinite number, which a case file cannot hold (its numbers are checked finite), and of a
    value of any other type: ``json.dumps`` would refuse either without naming its key."""
    if isinstance(value, dict):
        table = {}
        for name, item in value.items():
            if not isinstance(name, str):
                raise ValueError(f"{key or 'the case'}: the key {name!r} is not a string")
            table[name] = plain(item, f"{key}.{name}" if key else name)
        return table
    if isinstance(value, (list, tuple)):
        return [plain(item, f"{key}[{k}]") for k, item in enumerate(value)]
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        return plain(value.tolist(), key)
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    # Decimal is not a numbers.Real (it refuses to mix with floats), but is a number a user
    # reads off a table as surely as a float.
    if isinstance(value, (numbers.Real, decimal.Decimal)):
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if math.isfinite(number):
            return number
        if math.isnan(number):
            raise ValueError(f"{key}: NaN is not a number a case can hold (a case's numbers "
                             "are finite)")
        raise ValueError(f"{key}: {value!r} is not a number a case can hold (a case's numbers "
                         "are finite)")
    raise ValueError(f"{key}: a value of type {type(value).__name__} ({value!r}) is not a case "
                     "value: expected a number, a string, a bool, a list or a dict")
