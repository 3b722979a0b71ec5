"""A small model of a terminal screen, to see what a user would see of a byte stream.

It knows what prompt-toolkit and rich write when drawing a prompt or a line: text,
CR, LF (with the CR a tty adds), backspace, and the CSI sequences that move the
cursor (A B C D G H) or erase (J K); colours, modes and titles change nothing here.
The screen grows downwards without scrolling, so every line ever written stays.
"""

from __future__ import annotations

import re

_CSI = re.compile(r"\x1b\[([0-9;?]*)([@-~])")
_OSC = re.compile(r"\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)")
_OTHER_ESCAPE = re.compile(r"\x1b[()][0-9A-Za-z]|\x1b[=>78]")


class Screen:
    def __init__(self, width: int) -> None:
        self.width = width
        self.rows: list[list[str]] = [[]]
        self.row = 0
        self.col = 0

    def feed(self, text: str) -> Screen:
        """Play ``text`` onto the screen (one call or many: the same screen)."""
        at = 0
        while at < len(text):
            char = text[at]
            if char == "\x1b":
                for pattern in (_CSI, _OSC, _OTHER_ESCAPE):
                    match = pattern.match(text, at)
                    if match:
                        if pattern is _CSI:
                            self._csi(match.group(1), match.group(2))
                        at = match.end()
                        break
                else:
                    at += 1  # a lone ESC: nothing drawn
                continue
            if char == "\r":
                self.col = 0
            elif char == "\n":  # the tty's ONLCR: a new line starts at column 0
                self._move(self.row + 1, 0)
            elif char == "\b":
                self.col = max(0, self.col - 1)
            elif char >= " ":
                self._put(char)
            at += 1
        return self

    def lines(self) -> list[str]:
        """Every line, trailing blanks taken off."""
        return ["".join(row).rstrip() for row in self.rows]

    def _put(self, char: str) -> None:
        if self.col >= self.width:  # autowrap
            self._move(self.row + 1, 0)
        line = self.rows[self.row]
        if len(line) <= self.col:
            line.extend(" " * (self.col + 1 - len(line)))
        line[self.col] = char
        self.col += 1

    def _move(self, row: int, col: int) -> None:
        self.row, self.col = max(0, row), max(0, min(col, self.width))
        while len(self.rows) <= self.row:
            self.rows.append([])

    def _csi(self, params: str, final: str) -> None:
        if params.startswith("?"):
            return  # private modes: cursor shown or hidden, bracketed paste, ...
        numbers = [int(p) if p else 0 for p in params.split(";")] if params else []
        n = numbers[0] if numbers and numbers[0] else 1
        if final == "A":
            self._move(self.row - n, self.col)
        elif final == "B":
            self._move(self.row + n, self.col)
        elif final == "C":
            self._move(self.row, self.col + n)
        elif final == "D":
            self._move(self.row, self.col - n)
        elif final == "G":
            self._move(self.row, n - 1)
        elif final in "Hf":
            row = numbers[0] if numbers and numbers[0] else 1
            col = numbers[1] if len(numbers) > 1 and numbers[1] else 1
            self._move(row - 1, col - 1)
        elif final == "J":
            mode = numbers[0] if numbers else 0
            if mode == 0:
                del self.rows[self.row][self.col :]
                del self.rows[self.row + 1 :]
            elif mode in (2, 3):
                self.rows = [[] for _ in self.rows]
        elif final == "K":
            mode = numbers[0] if numbers else 0
            line = self.rows[self.row]
            if mode == 0:
                del line[self.col :]
            elif mode == 1:
                line[: self.col] = [" "] * min(self.col, len(line))
            else:
                line.clear()
