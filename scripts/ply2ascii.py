#!/usr/bin/env python3
"""ply2ascii.py: a PLY file (binary_little_endian or ASCII, as ndcontour writes mesh.ply,
input.ply and ruled.ply) as ASCII PLY on standard output.

    python3 scripts/ply2ascii.py FILE.ply > FILE-ascii.ply

The header is copied with its format line changed to `format ascii 1.0`; each record becomes one
line of values separated by blanks (a list: its length, then its items). ASCII input is copied
unchanged. Bad input (not PLY, big-endian, a count the file cannot hold, a file that ends early
or has bytes after its last element) is one line on standard error and exit status 2.
Only the Python standard library (struct) is used.
"""
import struct
import sys

TYPES = {
    "char": "b", "int8": "b", "uchar": "B", "uint8": "B",
    "short": "h", "int16": "h", "ushort": "H", "uint16": "H",
    "int": "i", "int32": "i", "uint": "I", "uint32": "I",
    "float": "f", "float32": "f", "double": "d", "float64": "d",
}


class BadPly(Exception):
    pass


def read_header(data):
    """The header lines (text), whether the body is binary, the elements and the body offset."""
    end = data.find(b"end_header")
    newline = data.find(b"\n", end) if end >= 0 else -1
    lines = data[:newline + 1].decode("ascii", "replace").splitlines()
    if newline < 0 or lines[0].rstrip() != "ply":
        raise BadPly("not a PLY file, or the header has no end_header")
    binary = None
    elements = []  # [name, count, [(name, type, count_type or None)]]
    for line in lines[1:]:
        w = line.split()
        if not w or w[0] in ("comment", "obj_info", "end_header"):
            continue
        if w[0] == "format":
            if w[1:] not in (["ascii", "1.0"], ["binary_little_endian", "1.0"]):
                raise BadPly("format '%s' is not read (only ascii and binary_little_endian)"
                             % " ".join(w[1:]))
            binary = w[1] != "ascii"
        elif w[0] == "element" and len(w) == 3 and w[2].isdigit():
            elements.append([w[1], int(w[2]), []])
        elif w[0] == "property" and elements and len(w) == 3 and w[1] in TYPES:
            elements[-1][2].append((w[2], TYPES[w[1]], None))
        elif (w[0] == "property" and elements and len(w) == 5 and w[1] == "list"
              and w[2] in TYPES and w[3] in TYPES):
            elements[-1][2].append((w[4], TYPES[w[3]], TYPES[w[2]]))
        else:
            raise BadPly("bad header line '%s'" % line[:80])
    if binary is None:
        raise BadPly("the header has no format line")
    return lines, binary, elements, newline + 1


def text(value):
    return repr(value) if isinstance(value, float) else str(value)


def records(data, at, name, count, props, out):
    """Writes `count` records of one element starting at byte `at`; returns the next offset."""
    if all(p[2] is None for p in props):  # fixed size: one struct for the whole block
        record = struct.Struct("<" + "".join(p[1] for p in props))
        if record.size * count > len(data) - at:
            raise BadPly("element '%s' declares %d records, more than the file holds"
                         % (name, count))
        block = data[at:at + record.size * count]
        out.writelines(" ".join(map(text, r)) + "\n" for r in record.iter_unpack(block))
        return at + record.size * count
    for i in range(count):
        values = []
        for _, item, length in props:
            try:
                if length is None:
                    values.append(struct.unpack_from("<" + item, data, at)[0])
                    at += struct.calcsize(item)
                    continue
                n = struct.unpack_from("<" + length, data, at)[0]
                at += struct.calcsize(length)
                values.append(n)
                values.extend(struct.unpack_from("<%d%s" % (n, item), data, at))
                at += n * struct.calcsize(item)
            except struct.error:
                raise BadPly("ends inside element '%s' (record %d of %d)" % (name, i + 1, count))
        out.write(" ".join(map(text, values)) + "\n")
    return at


def main(argv):
    if len(argv) != 2:
        sys.stderr.write("usage: ply2ascii.py FILE.ply\n")
        return 2
    try:
        with open(argv[1], "rb") as f:
            data = f.read()
    except OSError as e:
        sys.stderr.write("ply2ascii.py: %s: cannot read the file: %s\n" % (argv[1], e.strerror))
        return 2
    try:
        lines, binary, elements, at = read_header(data)
        if not binary:
            sys.stdout.buffer.write(data)
            return 0
        out = sys.stdout
        for line in lines:
            out.write(("format ascii 1.0" if line.startswith("format ") else line) + "\n")
        for name, count, props in elements:
            at = records(data, at, name, count, props, out)
        if at != len(data):
            raise BadPly("%d bytes after the last element" % (len(data) - at))
    except BadPly as e:
        sys.stderr.write("ply2ascii.py: %s: %s\n" % (argv[1], e))
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
