"""Exact reference values shared by the tests."""

from fractions import Fraction


def pi_fraction(digits: int) -> Fraction:
    """pi to ``digits`` decimals, as an exact fraction (Machin's formula in integers)."""
    one = 10 ** (digits + 10)

    def arctan_inv(x: int) -> int:
        total = term = one // x
        x2, k, sign = x * x, 1, -1
        while term:
            term //= x2
            total += sign * (term // (2 * k + 1))
            sign, k = -sign, k + 1
        return total

    return Fraction(4 * (4 * arctan_inv(5) - arctan_inv(239)), one)
