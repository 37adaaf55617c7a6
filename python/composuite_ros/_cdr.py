"""Read chosen fields of a serialized ROS 2 message (XCDR1, little or big endian) without building
the whole Python message: the observation arrives once per step and rclpy's full conversion
(dozens of nested Point/Quaternion objects) was the agent loop's largest cost.

The layout comes from the generated message class itself (`SLOT_TYPES`, i.e. the .msg file), so
nothing here restates a message's fields:

    reader = FieldReader(Observation, ["header.stamp.sec", "episode", "flat"])
    values = reader.read(raw_bytes)   # {"header.stamp.sec": 12, "episode": 3, "flat": ndarray}
"""

from __future__ import annotations

import importlib
import struct
from dataclasses import dataclass

import numpy as np
from rosidl_parser.definition import (AbstractNestedType, AbstractString, Array, BasicType,
                                      NamespacedType)

# rosidl basic type → (struct format, size); CDR aligns each primitive to its size.
_PRIMITIVES = {
    "boolean": ("?", 1), "octet": ("B", 1), "char": ("B", 1), "uint8": ("B", 1), "int8": ("b", 1),
    "uint16": ("H", 2), "int16": ("h", 2), "uint32": ("I", 4), "int32": ("i", 4),
    "uint64": ("Q", 8), "int64": ("q", 8), "float": ("f", 4), "double": ("d", 8),
}


@dataclass
class _Op:
    name: str | None  # None: skipped
    kind: str         # "fixed" (count primitives), "string", "sequence" (of primitives), "strings"
    fmt: str = ""
    size: int = 0     # of one element, also its alignment
    count: int = 1


def _message_class(t: NamespacedType):
    module = importlib.import_module(".".join(t.namespaces))
    return getattr(module, t.name)


def _compile(cls, prefix: str, wanted: set[str]) -> list[_Op]:
    ops: list[_Op] = []
    for field, slot in zip(cls.get_fields_and_field_types(), cls.SLOT_TYPES):
        name = prefix + field
        keep = name if name in wanted else None
        if isinstance(slot, BasicType):
            fmt, size = _PRIMITIVES[slot.typename]
            ops.append(_Op(keep, "fixed", fmt, size))
        elif isinstance(slot, AbstractString):
            ops.append(_Op(keep, "string"))
        elif isinstance(slot, NamespacedType):
            if keep:
                raise ValueError(f"{name} is a message; ask for its fields")
            ops.extend(_compile(_message_class(slot), name + ".", wanted))
        elif (isinstance(slot, AbstractNestedType) and not isinstance(slot, Array)
              and isinstance(slot.value_type, AbstractString)):
            ops.append(_Op(keep, "strings"))
        elif isinstance(slot, AbstractNestedType) and isinstance(slot.value_type, BasicType):
            fmt, size = _PRIMITIVES[slot.value_type.typename]
            if isinstance(slot, Array):
                ops.append(_Op(keep, "fixed", fmt, size, slot.size))
            else:
                ops.append(_Op(keep, "sequence", fmt, size))
        else:
            raise ValueError(f"{name}: {type(slot).__name__} of messages/strings is not supported here")
    return ops


def _merge_skips(ops: list[_Op]) -> list[_Op]:
    """Runs of skipped fixed fields of one element size are one skip (no padding between them)."""
    merged: list[_Op] = []
    for op in ops:
        last = merged[-1] if merged else None
        if (op.name is None and op.kind == "fixed" and last is not None and last.name is None
                and last.kind == "fixed" and last.size == op.size):
            last.count += op.count
        else:
            merged.append(_Op(op.name, op.kind, op.fmt, op.size, op.count))
    return merged


class FieldReader:
    """Reads `fields` (dotted paths to primitive, string or primitive-array fields) of `cls`."""

    def __init__(self, cls, fields: list[str]):
        wanted = set(fields)
        ops = _compile(cls, "", wanted)
        missing = wanted - {op.name for op in ops}
        if missing:
            raise ValueError(f"{cls.__name__} has no field(s) {sorted(missing)}")
        self.ops = _merge_skips(ops)

    def read(self, data: bytes) -> dict:
        try:
            return self._read(data)
        except struct.error as err:  # a length or count read past the end
            raise ValueError(f"message ends at byte {len(data) - 4}: {err}") from None

    def _read(self, data: bytes) -> dict:
        if len(data) < 4:
            raise ValueError("too short for a CDR encapsulation header")
        little = data[1] & 1 == 1  # CDR_LE = 0x0001, CDR_BE = 0x0000
        order = "<" if little else ">"
        body = memoryview(data)[4:]
        offset = 0
        values = {}
        for op in self.ops:
            if op.kind == "string":
                text, offset = _read_string(body, offset, order)
                if op.name:
                    values[op.name] = text
                continue
            if op.kind == "strings":
                offset += -offset % 4
                (count,) = struct.unpack_from(order + "I", body, offset)
                offset += 4
                texts = []
                for _ in range(count):
                    text, offset = _read_string(body, offset, order)
                    texts.append(text)
                if op.name:
                    values[op.name] = texts
                continue
            count = op.count
            if op.kind == "sequence":
                offset += -offset % 4
                (count,) = struct.unpack_from(order + "I", body, offset)
                offset += 4
            offset += -offset % op.size if count else 0
            end = offset + op.size * count
            if end > len(body):
                raise ValueError(f"message ends at byte {len(body)}, field {op.name or '(skipped)'} needs {end}")
            if op.name:
                if op.kind == "fixed" and op.count == 1:
                    (values[op.name],) = struct.unpack_from(order + op.fmt, body, offset)
                else:
                    values[op.name] = np.frombuffer(body[offset:end], dtype=np.dtype(order + op.fmt)).copy()
            offset = end
        return values


def _read_string(body: memoryview, offset: int, order: str) -> tuple[str, int]:
    """A CDR string at `offset` (4-aligned length including the NUL, then the bytes): the text and
    the offset after it."""
    offset += -offset % 4
    (length,) = struct.unpack_from(order + "I", body, offset)
    end = offset + 4 + length
    if end > len(body):
        raise ValueError(f"message ends at byte {len(body)}, a string needs {end}")
    return bytes(body[offset + 4:end - 1]).decode(), end
