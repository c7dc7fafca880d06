"""Array layouts declared once: a small allocator of named slots.

Each of tlm's state and configuration arrays (the truth state ``x``, the sensor state ``s``,
the EKF lane rows, the controller state ``c``, their configurations) is a flat float64 array
whose slots the jitted kernels address through module constants (``x[PN]``, ``c[MIX_PWM + i]``).
A :class:`Layout` hands those constants out: each :meth:`Layout.add` takes the next free slots,
so two names can never share one, and records the name, width, unit and meaning once::

    X = Layout("x", "truth state")
    PN = X.add("PN", unit="m", doc="position north of home")
    VEL = X.add("VEL", 3, "m/s", "velocity NED")
    N_STATE = X.close()

A record that repeats (one block of rate-PID slots per axis, one block per IMU) is a layout of
its own, placed ``count`` times with :meth:`Layout.block`; its constants are offsets within
the record, the block's start is the base (``s[IMU_BASE + i * IMU_STRIDE + I_DANG]``).

The constants stay plain ``int`` module globals, so numba folds them into the machine code as
before. :meth:`Layout.describe` gives a named view of an array for debugging, and
``tests/test_layouts.py`` checks every layout: its slots cover the array once, each module
constant equals the slot of its name.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # numpy only for describe(), so the plain-constant modules
    import numpy as np  # (tlm_sim.ardupilot) can declare layouts without importing it

__all__ = ["Layout", "Slot"]


@dataclass(frozen=True)
class Slot:
    """``width`` consecutive elements from ``start`` of a layout (a record ``layout`` placed
    ``width // layout.size`` times, for a block)."""

    name: str
    start: int
    width: int
    unit: str = ""
    doc: str = ""
    record: Layout | None = None

    @property
    def stop(self) -> int:
        """One past the last element."""
        return self.start + self.width


class Layout:
    """Slots of one flat array, handed out consecutively (see the module docstring)."""

    def __init__(self, name: str, doc: str = "") -> None:
        self.name = name
        self.doc = doc
        self._slots: dict[str, Slot] = {}
        self._size = 0
        self._closed = False

    # -- declaring ----------------------------------------------------------------------------
    def add(self, name: str, width: int = 1, unit: str = "", doc: str = "") -> int:
        """The next ``width`` free slots, named ``name``; returns the first one's index."""
        return self._take(Slot(name, self._size, self._check_width(name, width), unit, doc))

    def vector(self, names: tuple[str, ...] | list[str], unit: str = "",
               doc: str = "") -> tuple[int, ...]:
        """One slot per name, consecutive (``PN, PE, PD = X.vector(("PN", "PE", "PD"), "m",
        "position NED")``); returns their indices."""
        return tuple(self.add(n, 1, unit, doc) for n in names)

    def block(self, name: str, record: Layout, count: int = 1, doc: str = "") -> int:
        """``count`` copies of the closed layout ``record`` (stride ``record.size``); returns
        the first copy's start (the block's base)."""
        if not record._closed:
            raise ValueError(f"{self.name}.{name}: record layout {record.name} is not closed")
        width = self._check_width(name, record.size * count)
        return self._take(Slot(name, self._size, width, "", doc or record.doc, record))

    def close(self) -> int:
        """End the layout (no more slots); returns its size."""
        self._closed = True
        return self._size

    def _check_width(self, name: str, width: int) -> int:
        if isinstance(width, bool) or not isinstance(width, int) or width < 1:
            raise ValueError(f"{self.name}.{name}: width must be a whole number >= 1, "
                             f"got {width!r}")
        return width

    def _take(self, slot: Slot) -> int:
        if self._closed:
            raise ValueError(f"{self.name} is closed; {slot.name} comes too late")
        if slot.name in self._slots:
            raise ValueError(f"{self.name}: slot {slot.name} declared twice")
        self._slots[slot.name] = slot
        self._size = slot.stop
        return slot.start

    # -- reading ------------------------------------------------------------------------------
    @property
    def size(self) -> int:
        """Elements in the array."""
        return self._size

    def __iter__(self) -> Iterator[Slot]:
        return iter(self._slots.values())

    def __len__(self) -> int:
        return len(self._slots)

    def __getitem__(self, name: str) -> Slot:
        return self._slots[name]

    def __repr__(self) -> str:
        return f"Layout({self.name!r}, {len(self)} slots, size {self.size})"

    def name_of(self, index: int) -> str:
        """The name of element ``index`` (``"IMU[1].I_DANG[2]"`` inside a block's record)."""
        if not 0 <= index < self._size:
            raise IndexError(f"{self.name} has no element {index} (size {self._size})")
        for slot in self._slots.values():
            if slot.start <= index < slot.stop:
                off = index - slot.start
                if slot.record is not None:
                    k, rest = divmod(off, slot.record.size)
                    return f"{slot.name}[{k}].{slot.record.name_of(rest)}"
                return slot.name if slot.width == 1 else f"{slot.name}[{off}]"
        raise AssertionError("slots cover the layout")  # pragma: no cover

    def describe(self, array: np.ndarray) -> dict[str, Any]:
        """A named view of ``array`` (one row of this layout): name -> float for a one-wide
        slot, name -> array view for a wider one, name -> list of record views for a block."""
        import numpy as np

        a = np.asarray(array)
        if a.shape != (self._size,):
            raise ValueError(f"{self.name} describes arrays of shape ({self._size},), got "
                             f"{a.shape}")
        out: dict[str, Any] = {}
        for slot in self._slots.values():
            part = a[slot.start:slot.stop]
            if slot.record is not None:
                n = slot.record.size
                out[slot.name] = [slot.record.describe(part[k * n:(k + 1) * n])
                                  for k in range(slot.width // n)]
            else:
                out[slot.name] = float(part[0]) if slot.width == 1 else part
        return out

    def table(self) -> list[dict[str, Any]]:
        """One row per slot: name, start, width, unit, doc (for docs and ``tlm`` listings)."""
        return [{"name": s.name, "start": s.start, "width": s.width, "unit": s.unit,
                 "doc": s.doc} for s in self._slots.values()]
