"""Argument types of the command line: each turns a bad value into one line naming it and what was expected."""

from __future__ import annotations

import argparse
import math

__all__ = ["Parser", "count", "float_list", "int_list", "positive_float", "positive_int", "whole_number"]


class Parser(argparse.ArgumentParser):
    """argparse with its errors on one line (no usage block): ``mechopt study: error: …`` and exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def whole_number(minimum: int):
    """An argparse type: a whole number >= ``minimum``, or a one-line error naming the value."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number >= {minimum}")
        return value

    return parse


positive_int = whole_number(1)
count = whole_number(0)


def positive_float(text: str) -> float:
    """An argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a finite number > 0")
    return value


def int_list(text: str) -> list[int]:
    """An argparse type: comma-separated simulation budgets of ``mechopt compare``."""
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of integers") from None
    if not values or min(values) < 10:
        raise argparse.ArgumentTypeError(f"budgets {text!r}: expected integers >= 10")
    return values


def float_list(text: str) -> list[float]:
    """An argparse type: a design's values, comma-separated (``--x0 30,70.5,254``); its shape and bounds are the
    problem's to check."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of numbers") from None
    return values
