"""fuzz_body_files.py's byte-level families: sealed, resealed and checksummed (HDF5's lookup3 recomputed)."""
import re


from fuzz_base import METADATA_BYTES, SEAL, seal_bytes


# ----------------------------------------------------------------------------------------------------------------
# Families sealed and resealed: byte-level changes


def byte_mutation(good, meta, rng, index, floor):
    """A changed copy of `good` (never equal to it) at or after byte `floor`, and what was done. index % 4: 0 and
    2 aim at the first 4 KiB after `floor`, 1 at HDF5 metadata (outside the datasets' raw data), 3 anywhere."""
    size = len(good)
    aim = ("first 4 KiB", "metadata", "first 4 KiB", "anywhere")[index % 4]

    def position(span=1):
        """A position p with p + span <= size, aimed as above."""
        if aim == "first 4 KiB":
            return rng.randrange(floor, max(floor + 1, min(size - span + 1, floor + METADATA_BYTES)))
        if aim == "metadata":
            usable = [(b, min(e, size - span + 1)) for b, e in meta if min(e, size - span + 1) > b]
            if usable:
                total = sum(e - b for b, e in usable)
                k = rng.randrange(total)
                for b, e in usable:
                    if k < e - b:
                        return b + k
                    k -= e - b
        return rng.randrange(floor, size - span + 1)

    for _ in range(100):
        data = bytearray(good)
        kind = rng.choice(("bit flip", "bit flip", "zeroed block", "truncation", "random byte", "0xff x 8",
                           "random 8 bytes", "splice"))
        if kind == "bit flip":
            at, bit = position(), rng.randrange(8)
            data[at] ^= 1 << bit
            what = f"bit {bit} of byte {at} flipped"
        elif kind == "zeroed block":
            length = rng.choice((1, 4, 8, 16, 64))
            at = position(length)
            data[at:at + length] = bytes(length)
            what = f"bytes {at} to {at + length - 1} zeroed"
        elif kind == "truncation":
            length = max(position(), floor + 1)
            del data[length:]
            what = f"truncated to {length} bytes"
        elif kind == "random byte":
            at = position()
            data[at] = rng.randrange(256)
            what = f"byte {at} set to {data[at]}"
        elif kind == "0xff x 8":
            at = position(8)
            data[at:at + 8] = b"\xff" * 8
            what = f"bytes {at} to {at + 7} set to 0xff"
        elif kind == "random 8 bytes":  # e.g. an address or a length of HDF5's 8 bytes
            at = position(8)
            value = rng.choice((rng.getrandbits(64), rng.getrandbits(32), 1 << rng.randrange(64)))
            data[at:at + 8] = value.to_bytes(8, "little")
            what = f"bytes {at} to {at + 7} set to {value} (little-endian 64 bits)"
        else:  # splice: copy a block of the file over another place (a plausible-looking header or address)
            length = rng.choice((8, 16, 32, 64))
            at, source = position(length), rng.randrange(floor, size - length + 1)
            data[at:at + length] = good[source:source + length]
            what = f"bytes {source} to {source + length - 1} copied over bytes {at} to {at + length - 1}"
        if bytes(data) != good:
            return bytes(data), f"{kind} ({aim}): {what}"
    raise RuntimeError("no change found")


M = 0xFFFFFFFF
def _rot(x, k): return ((x << k) | (x >> (32 - k))) & M
def lookup3(data, initval=0):
    """Bob Jenkins' lookup3 hashlittle, as HDF5's H5_checksum_lookup3 (the checksum of its version-2 metadata)."""
    length = len(data)
    a = b = c = (0xdeadbeef + length + initval) & M
    i = 0
    while length > 12:
        a = (a + int.from_bytes(data[i:i + 4], "little")) & M
        b = (b + int.from_bytes(data[i + 4:i + 8], "little")) & M
        c = (c + int.from_bytes(data[i + 8:i + 12], "little")) & M
        a = (a - c) & M; a ^= _rot(c, 4); c = (c + b) & M
        b = (b - a) & M; b ^= _rot(a, 6); a = (a + c) & M
        c = (c - b) & M; c ^= _rot(b, 8); b = (b + a) & M
        a = (a - c) & M; a ^= _rot(c, 16); c = (c + b) & M
        b = (b - a) & M; b ^= _rot(a, 19); a = (a + c) & M
        c = (c - b) & M; c ^= _rot(b, 4); b = (b + a) & M
        length -= 12
        i += 12
    if length == 0:
        return c
    tail = bytes(data[i:i + length]) + bytes(12 - length)
    a = (a + int.from_bytes(tail[0:4], "little")) & M
    b = (b + int.from_bytes(tail[4:8], "little")) & M
    c = (c + int.from_bytes(tail[8:12], "little")) & M
    c ^= b; c = (c - _rot(b, 14)) & M
    a ^= c; a = (a - _rot(c, 11)) & M
    b ^= a; b = (b - _rot(a, 25)) & M
    c ^= b; c = (c - _rot(b, 16)) & M
    a ^= c; a = (a - _rot(c, 4)) & M
    b ^= a; b = (b - _rot(a, 14)) & M
    c ^= b; c = (c - _rot(b, 24)) & M
    return c


def checksummed_structures(data):
    """[(begin, end)] of the checksummed HDF5 metadata through which a change reaches the parser: the version-2
    superblock and every version-2 object header (each OHDR chunk 0 and the OCHK continuation chunks its
    continuation messages point to), each ending in its lookup3 checksum. Only structures whose stored checksum
    matches are listed (a signature found inside raw data is not one)."""
    base = SEAL
    if data[base:base + 8] != b"\x89HDF\r\n\x1a\n" or data[base + 8] not in (2, 3):
        return []
    out = [(base, base + 48)]

    def continuations(begin, end, flags):  # the (address, length) of every continuation message in a chunk
        pos = begin
        while pos + 4 <= end:
            kind, size = data[pos], int.from_bytes(data[pos + 1:pos + 3], "little")
            pos += 4 + (2 if flags & 0x04 else 0)
            if kind == 0x10 and size >= 16:
                yield int.from_bytes(data[pos:pos + 8], "little"), int.from_bytes(data[pos + 8:pos + 16], "little")
            pos += size

    for match in re.finditer(b"OHDR", data):
        at = match.start()
        flags, pos = data[at + 5], at + 6
        pos += (16 if flags & 0x20 else 0) + (4 if flags & 0x10 else 0)
        n = 1 << (flags & 3)
        size = int.from_bytes(data[pos:pos + n], "little")
        pos += n
        chunks = [(at, pos + size + 4, pos, pos + size)]
        for _, _, messages_begin, messages_end in chunks:  # grows while continuation chunks are found
            for address, length in continuations(messages_begin, messages_end, flags):
                c0 = base + address
                if data[c0:c0 + 4] == b"OCHK" and 8 <= length and c0 + length <= len(data):
                    chunks.append((c0, c0 + length, c0 + 4, c0 + length - 4))
        for begin, end, _, _ in chunks:
            if end <= len(data) and lookup3(data[begin:end - 4]) == int.from_bytes(data[end - 4:end], "little"):
                out.append((begin, end))
    return sorted(set(out))


def checksummed_mutation(good, structures, rng):
    """A change inside one checksummed structure (after its signature), its lookup3 checksum recomputed, the
    seal recomputed: what an attacker who knows the format can hand libhdf5."""
    for _ in range(100):
        begin, end = rng.choice(structures)
        data = bytearray(good)
        lo, hi = begin + 4, end - 4  # keep the signature, then the checksum is written anew
        kind = rng.choice(("bit flip", "bit flip", "random byte", "zeroed bytes", "0xff x 8", "random 8 bytes",
                           "small integer"))
        if kind == "bit flip":
            at, bit = rng.randrange(lo, hi), rng.randrange(8)
            data[at] ^= 1 << bit
            what = f"bit {bit} of byte {at}"
        elif kind == "random byte":
            at = rng.randrange(lo, hi)
            data[at] = rng.randrange(256)
            what = f"byte {at} = {data[at]}"
        elif kind == "zeroed bytes":
            length = min(rng.choice((1, 2, 4, 8)), hi - lo)
            at = rng.randrange(lo, hi - length + 1)
            data[at:at + length] = bytes(length)
            what = f"bytes {at} to {at + length - 1} zeroed"
        else:
            length = min(8 if kind != "small integer" else rng.choice((1, 2, 4)), hi - lo)
            at = rng.randrange(lo, hi - length + 1)
            value = {"0xff x 8": (1 << (8 * length)) - 1, "random 8 bytes": rng.getrandbits(8 * length),
                     "small integer": rng.choice((0, 1, 2, 3, 7, 8, 255, 256, 65535))}[kind] % (1 << (8 * length))
            data[at:at + length] = value.to_bytes(length, "little")
            what = f"bytes {at} to {at + length - 1} = {value}"
        data[end - 4:end] = lookup3(bytes(data[begin:end - 4])).to_bytes(4, "little")
        if bytes(data) != good:
            sig = bytes(good[begin:begin + 4]).decode("latin-1")
            sig = "superblock" if sig.startswith("\x89HD") else sig
            return seal_bytes(bytes(data)), f"{kind} in {sig} at {begin}..{end}: {what}, checksum recomputed"
    raise RuntimeError("no change found")
