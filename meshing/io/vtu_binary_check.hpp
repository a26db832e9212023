// Internal: a pre-flight check of a VTK XML unstructured grid file, run before the file is handed
// to VTK's reader, so that corrupted files become InputErrors instead of crashes.
//
// Why: VTK 9.1's XML reader trusts what the file says. Measured here with byte-flipping fuzzing:
//   * a compression header with block size 0 → division by zero (SIGFPE, the process dies);
//   * no blocks but a partial last block → size underflow, reads block 0 (SIGSEGV);
//   * a huge block count or compressed block size → terabyte allocations;
//   * NumberOfPoints / NumberOfCells / a last cell offset larger than the data → the array
//     allocation fails or overflows and VTK then writes past a small buffer (heap corruption).
// This check bounds every binary array (raw or base64 appended data, inline base64 "binary"
// arrays, zlib/LZ4/LZMA-compressed or not) and every ascii array by what the file actually
// contains, and the connectivity length by the last cell offset (decoded from the offsets array;
// zlib is used to decode a compressed one, LZ4/LZMA-compressed offsets are not decoded).
//
// Not covered (VTK's own checks apply): polyhedron face streams, field data of other dataset types.
// Random corruption inside zlib-compressed data is caught by zlib's checksum.
#pragma once

#include <string>

namespace curvefem::io::detail {

/// `bytes`: the whole file; `file`: its name for error messages. Throws InputError (with a byte
/// offset) for an inconsistency VTK's reader would not survive; returns silently otherwise,
/// including for anything it does not recognise (VTK then reports it).
void check_vtu_before_vtk(const std::string& bytes, const std::string& file);

}  // namespace curvefem::io::detail
