"""Capture the RTPS traffic one host sends over a scripted-pair link and check, with a parser of
its own (independent of every DDS implementation in the test), that each DATA_FRAG submessage is
exactly as long as its header declares — the property RustDDS 0.15.1 broke for DATA_FRAGs with
inline QoS (a service reply, fragmented).

    python rtps_capture.py --interface veth-b --source 198.18.0.1 > summary.json

Runs until SIGINT/SIGTERM, then prints a JSON summary: datagrams seen, DATA_FRAG submessages (with
inline QoS: how many, their sample sizes), and every malformed message found. IPv4 fragments are
reassembled first (datagrams of up to ~1.5 kB plus inline QoS can exceed a 1500-byte MTU). Needs
root (a packet socket); run it in the namespace whose link it should watch."""

from __future__ import annotations

import argparse
import json
import signal
import socket
import struct
import sys

ETH_P_IP = 0x0800
DATA_FRAG = 0x16
FLAG_LITTLE_ENDIAN, FLAG_INLINE_QOS = 0x01, 0x02
PID_SENTINEL = 0x0001
# RTPS 2.x: submessages after which octetsToNextHeader 0 means "to the end of the message".
LAST_MAY_BE_ZERO = {0x01}  # PAD; any other kind with 0 extends to the end as well (9.4.5.1.3)


class Malformed(ValueError):
    pass


def parse_parameter_list(body: bytes, offset: int, endian: str) -> tuple[int, list[int]]:
    """(offset after the sentinel, parameter ids) of the parameter list at `offset`."""
    pids = []
    while True:
        if offset + 4 > len(body):
            raise Malformed(f"parameter list runs past the submessage (at {offset} of {len(body)})")
        pid, length = struct.unpack_from(endian + "HH", body, offset)
        offset += 4
        if pid == PID_SENTINEL:
            return offset, pids
        if length % 4 or offset + length > len(body):
            raise Malformed(f"parameter 0x{pid:04x} of length {length} does not fit "
                            f"(at {offset} of {len(body)})")
        pids.append(pid)
        offset += length


def check_data_frag(body: bytes, flags: int) -> dict:
    """The DATA_FRAG's declared fields, after checking its parts fill the body exactly."""
    endian = "<" if flags & FLAG_LITTLE_ENDIAN else ">"
    if len(body) < 32:
        raise Malformed(f"DATA_FRAG body of {len(body)} bytes, shorter than its fixed fields")
    octets_to_qos = struct.unpack_from(endian + "H", body, 2)[0]
    start, count, frag_size, sample_size = struct.unpack_from(endian + "IHHI", body, 20)
    offset = 4 + octets_to_qos
    pids: list[int] = []
    if flags & FLAG_INLINE_QOS:
        offset, pids = parse_parameter_list(body, offset, endian)
    payload = len(body) - offset
    if frag_size == 0 or start == 0:
        raise Malformed(f"fragment size {frag_size}, first fragment {start}")
    expected = min(count * frag_size, sample_size - (start - 1) * frag_size)
    # The payload is the fragments, at most padded to the next multiple of 4.
    if not expected <= payload < expected + 4:
        raise Malformed(f"DATA_FRAG payload of {payload} bytes where fragments {start}..{start + count - 1} "
                        f"of {frag_size} (sample {sample_size}) make {expected}")
    return {"inline_qos": bool(flags & FLAG_INLINE_QOS), "pids": pids, "sample_size": sample_size}


def check_rtps(message: bytes) -> list[dict]:
    """Every DATA_FRAG of one RTPS message, after checking the submessage chain ends exactly at
    the end of the datagram."""
    if len(message) < 20 or message[:4] != b"RTPS":
        return []
    frags, offset = [], 20
    while offset < len(message):
        if offset + 4 > len(message):
            raise Malformed(f"{len(message) - offset} stray byte(s) after the last submessage")
        kind, flags = message[offset], message[offset + 1]
        length = struct.unpack_from("<H" if flags & FLAG_LITTLE_ENDIAN else ">H", message, offset + 2)[0]
        body_start = offset + 4
        end = len(message) if length == 0 and kind not in LAST_MAY_BE_ZERO else body_start + length
        if end > len(message):
            raise Malformed(f"submessage 0x{kind:02x} declares {length} bytes, {len(message) - body_start} left")
        if kind == DATA_FRAG:
            frags.append(check_data_frag(message[body_start:end], flags))
        offset = end
    return frags


class Reassembler:
    """IPv4 datagrams from packets, fragments put back together."""

    def __init__(self):
        self.pending: dict[tuple, dict] = {}

    def add(self, packet: bytes) -> tuple[str, bytes] | None:
        """(source address, UDP payload) once a whole UDP datagram is there."""
        if len(packet) < 20 or packet[0] >> 4 != 4:
            return None
        ihl = (packet[0] & 0x0F) * 4
        total, ident, frag, _ttl, proto = struct.unpack_from("!HHHBB", packet, 2)
        if proto != socket.IPPROTO_UDP:
            return None
        source = socket.inet_ntoa(packet[12:16])
        more, offset = bool(frag & 0x2000), (frag & 0x1FFF) * 8
        data = packet[ihl:total]
        if not more and offset == 0:
            whole = data
        else:
            key = (packet[12:20], ident)
            entry = self.pending.setdefault(key, {"parts": {}, "size": None})
            entry["parts"][offset] = data
            if not more:
                entry["size"] = offset + len(data)
            if entry["size"] is None:
                return None
            joined, at = b"", 0
            for start in sorted(entry["parts"]):
                if start != at:
                    return None
                joined += entry["parts"][start]
                at = start + len(entry["parts"][start])
            if at != entry["size"]:
                return None
            del self.pending[key]
            whole = joined
        return source, whole[8:]  # past the UDP header


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--interface", required=True)
    parser.add_argument("--source", required=True, help="only datagrams from this IPv4 address")
    args = parser.parse_args()
    stop = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(True))
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_DGRAM, socket.htons(ETH_P_IP))
    sock.bind((args.interface, ETH_P_IP))
    sock.settimeout(0.1)
    print("capturing", file=sys.stderr, flush=True)
    reassembler = Reassembler()
    summary = {"datagrams": 0, "rtps": 0, "data_frags": 0, "data_frags_with_inline_qos": 0,
               "inline_qos_sample_sizes": [], "malformed_count": 0, "malformed": []}
    while not stop:
        try:
            packet = sock.recv(65536)
        except (TimeoutError, InterruptedError):
            continue
        datagram = reassembler.add(packet)
        if datagram is None or datagram[0] != args.source:
            continue
        summary["datagrams"] += 1
        payload = datagram[1]
        if payload[:4] != b"RTPS":
            continue
        summary["rtps"] += 1
        try:
            frags = check_rtps(payload)
        except Malformed as error:
            summary["malformed_count"] += 1
            if len(summary["malformed"]) < 20:
                summary["malformed"].append(str(error))
            continue
        for frag in frags:
            summary["data_frags"] += 1
            if frag["inline_qos"]:
                summary["data_frags_with_inline_qos"] += 1
                summary["inline_qos_sample_sizes"].append(frag["sample_size"])
    summary["inline_qos_sample_sizes"] = sorted(set(summary["inline_qos_sample_sizes"]))
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
