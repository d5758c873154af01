#include "run/checksum.hpp"

#include <zlib.h>

#include <cstdio>
#include <fstream>
#include <vector>

#include "lanechange/error.hpp"

namespace lanechange::run {

std::string file_crc32(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("", "cannot read " + path);
  uLong crc = crc32(0L, Z_NULL, 0);
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto got = static_cast<uInt>(in.gcount());
    if (got > 0) crc = crc32(crc, reinterpret_cast<const Bytef*>(buffer.data()), got);
  }
  char text[16];
  std::snprintf(text, sizeof text, "%08lx", static_cast<unsigned long>(crc));
  return text;
}

}  // namespace lanechange::run
