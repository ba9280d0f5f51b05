// Ray and hit files: bit-exact round trips, the byte layout, and every error message.

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "base/error.h"
#include "io/rayfile.h"
#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"

namespace rp {
namespace {

namespace fs = std::filesystem;
using test::error_of;

using test::TempDir;

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
float from_bits(uint32_t b) { return std::bit_cast<float>(b); }

std::array<uint32_t, 8> bits(const Ray& r) {
  return {bits(r.org.x), bits(r.org.y), bits(r.org.z), bits(r.dir.x),
          bits(r.dir.y), bits(r.dir.z), bits(r.tnear), bits(r.tfar)};
}
std::array<uint32_t, 8> bits(const HitRecord& h) {
  return {bits(h.t), h.prim_id, bits(h.u), bits(h.v), bits(h.ng.x), bits(h.ng.y), bits(h.ng.z), h.instance_id};
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(bytes.data(), std::streamsize(bytes.size()));
  ASSERT_TRUE(f.good()) << path;
}
std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

/// A 16-byte binary header.
std::string header(const char* magic, uint32_t version, uint64_t count) {
  std::string h(16, '\0');
  std::memcpy(h.data(), magic, 4);
  std::memcpy(h.data() + 4, &version, 4);
  std::memcpy(h.data() + 8, &count, 8);
  return h;
}

/// Float bit patterns a file must carry unchanged: signed zeros, denormals, extremes,
/// infinities and (where the format allows) NaNs with sign and payload.
const std::vector<uint32_t> kSpecialBits = {
    0x00000000, 0x80000000,              // +0, -0
    0x00000001, 0x80000001, 0x007fffff,  // smallest denormals, largest denormal
    0x00800000, 0x7f7fffff, 0xff7fffff,  // FLT_MIN, ±FLT_MAX
    0x7f800000, 0xff800000,              // ±inf
    0x3f800000, 0xbfc00000, 0x3eaaaaab,  // 1, -1.5, 1/3
    0x3dcccccd, 0x4b800001, 0x2edbe6ff,  // 0.1, 2^24+2, 1e-10
    0x7fc00000, 0xffc00001, 0x7fc12345,  // quiet NaNs (sign, payload)
    0x7f800001,                          // signalling NaN
};

std::vector<Ray> special_rays() {
  std::vector<Ray> rays;
  const size_t n = kSpecialBits.size();
  for (size_t i = 0; i < n; ++i) {
    auto v = [&](size_t k) { return from_bits(kSpecialBits[(i + 3 * k) % n]); };
    rays.push_back({{v(0), v(1), v(2)}, v(6), {v(3), v(4), v(5)}, v(7)});
  }
  return rays;
}

std::vector<HitRecord> special_hits() {
  std::vector<HitRecord> hits;
  const size_t n = kSpecialBits.size();
  const uint32_t ids[] = {0, 1, 7, 4294967294u, kInvalidId};
  for (size_t i = 0; i < n; ++i) {
    auto v = [&](size_t k) { return from_bits(kSpecialBits[(i + 5 * k) % n]); };
    hits.push_back({v(0), ids[i % 5], v(1), v(2), {v(3), v(4), v(5)}, ids[(i + 2) % 5]});
  }
  hits.push_back(HitRecord{});  // a miss
  return hits;
}

/// Rays made of seeded random bit patterns (NaNs included), enough to cross read/write chunks.
std::vector<Ray> bit_pattern_rays(size_t n) {
  std::mt19937 rng(20240611);
  std::vector<Ray> rays(n);
  for (Ray& r : rays) {
    r.org = {from_bits(rng()), from_bits(rng()), from_bits(rng())};
    r.dir = {from_bits(rng()), from_bits(rng()), from_bits(rng())};
    r.tnear = from_bits(rng());
    r.tfar = from_bits(rng());
  }
  return rays;
}

/// CSV keeps every bit except a NaN's sign and payload: NaN reads back as some NaN.
void expect_csv_equal(const std::array<uint32_t, 8>& want, const std::array<uint32_t, 8>& got, size_t i) {
  for (size_t k = 0; k < 8; ++k) {
    if (std::isnan(from_bits(want[k])))
      EXPECT_TRUE(std::isnan(from_bits(got[k]))) << "ray " << i << " field " << k;
    else
      EXPECT_EQ(want[k], got[k]) << "ray " << i << " field " << k;
  }
}

TEST(RayFileBinary, RoundTripIsBitExact) {
  TempDir tmp;
  const std::string path = tmp / "rays.bin";
  for (const std::vector<Ray>& rays : {special_rays(), bit_pattern_rays(5000), std::vector<Ray>{}}) {
    write_rays(path, rays);
    EXPECT_EQ(fs::file_size(path), 16 + 32 * rays.size());
    const std::vector<Ray> back = read_rays(path);
    ASSERT_EQ(back.size(), rays.size());
    for (size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(bits(back[i]), bits(rays[i])) << "ray " << i;
  }
  // Every write went through a temporary that is gone now; reading wrote nothing.
  EXPECT_EQ(tmp.entries(), std::set<std::string>{"rays.bin"});
}

TEST(RayFileBinary, LayoutIsHeaderThenOrgDirTnearTfar) {
  TempDir tmp;
  const std::string path = tmp / "one.rays";
  const Ray r{{1, 2, 3}, 7, {4, 5, 6}, 8};
  write_rays(path, std::vector<Ray>{r, r});
  const std::string b = read_bytes(path);
  ASSERT_EQ(b.size(), 16u + 64u);
  EXPECT_EQ(b.substr(0, 16), header("RPRY", 1, 2));
  EXPECT_EQ(b.substr(0, 16), std::string("RPRY\x01\0\0\0\x02\0\0\0\0\0\0\0", 16));
  for (int rec = 0; rec < 2; ++rec)
    for (int k = 0; k < 8; ++k) {
      float f;
      std::memcpy(&f, b.data() + 16 + 32 * rec + 4 * k, 4);
      EXPECT_EQ(f, float(k + 1)) << "record " << rec << " field " << k;
    }
}

TEST(RayFileRead, AFifoOrADeviceIsRefusedWithoutBlocking) {
  TempDir tmp;
  const std::string fifo = tmp / "rays.bin";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // No writer ever opens the FIFO: a reader that opened it for real would block here forever.
  EXPECT_EQ(error_of([&] { read_rays(fifo); }), fifo + ": cannot read: not a regular file (a FIFO)");
  EXPECT_EQ(error_of([&] { read_hits("/dev/zero"); }), "/dev/zero: cannot read: not a regular file (a character device)");
  // A symlink is followed to what it names.
  const std::string link = tmp / "zero.csv";
  fs::create_symlink("/dev/zero", link);
  EXPECT_EQ(error_of([&] { read_rays(link); }), link + ": cannot read: not a regular file (a character device)");
}

/// Runs f with standard input reading `bytes` from a pipe (fed by a thread), then restores it.
template <typename F>
void with_stdin(const std::string& bytes, F&& f) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const int saved = ::dup(STDIN_FILENO);
  ::dup2(fds[0], STDIN_FILENO);
  ::close(fds[0]);
  std::thread writer([&] {
    size_t at = 0;
    while (at < bytes.size()) {
      const ssize_t n = ::write(fds[1], bytes.data() + at, bytes.size() - at);
      if (n <= 0) break;
      at += size_t(n);
    }
    ::close(fds[1]);
  });
  f();
  writer.join();
  ::dup2(saved, STDIN_FILENO);
  ::close(saved);
}

TEST(RayFileRead, DashReadsStandardInputInEitherFormat) {
  const std::vector<Ray> rays = bit_pattern_rays(3000);
  std::string bytes = header("RPRY", 1, rays.size());
  for (const Ray& r : rays) {
    const float f[8] = {r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tnear, r.tfar};
    bytes.append(reinterpret_cast<const char*>(f), 32);
  }
  std::vector<Ray> back;
  with_stdin(bytes, [&] { EXPECT_EQ(error_of([&] { back = read_rays("-"); }), test::kNoError); });
  ASSERT_EQ(back.size(), rays.size());
  for (size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(bits(back[i]), bits(rays[i])) << "ray " << i;
  with_stdin("ox,oy,oz,dx,dy,dz,tnear,tfar\n1,2,3,4,5,6,0,7\n", [&] { back = read_rays("-"); });
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].dir.z, 6.0f);
  with_stdin("RPRY", [&] { EXPECT_EQ(error_of([&] { read_rays("-"); }), "-: truncated: 4 bytes, the header needs 16"); });
}

TEST(HitFileBinary, RoundTripIsBitExact) {
  TempDir tmp;
  const std::string path = tmp / "hits.bin";
  std::vector<HitRecord> many(5000);
  std::mt19937 rng(7);
  for (HitRecord& h : many) h = {from_bits(rng()), uint32_t(rng()), from_bits(rng()), from_bits(rng()),
                                 {from_bits(rng()), from_bits(rng()), from_bits(rng())}, uint32_t(rng())};
  for (const std::vector<HitRecord>& hits : {special_hits(), many, std::vector<HitRecord>{}}) {
    write_hits(path, hits);
    EXPECT_EQ(fs::file_size(path), 16 + 32 * hits.size());
    const std::vector<HitRecord> back = read_hits(path);
    ASSERT_EQ(back.size(), hits.size());
    for (size_t i = 0; i < hits.size(); ++i) EXPECT_EQ(bits(back[i]), bits(hits[i])) << "hit " << i;
  }
  EXPECT_EQ(tmp.entries(), std::set<std::string>{"hits.bin"});
}

TEST(HitFileBinary, LayoutIsHeaderThenTPrimUVNormalInstance) {
  TempDir tmp;
  const std::string path = tmp / "hits";
  write_hits(path, std::vector<HitRecord>{{2.5f, 0x01020304u, 0.25f, 0.5f, {0, -1, 0}, 0x0a0b0c0du}});
  const std::string b = read_bytes(path);
  ASSERT_EQ(b.size(), 16u + 32u);
  EXPECT_EQ(b.substr(0, 16), std::string("RPHT\x02\0\0\0\x01\0\0\0\0\0\0\0", 16));  // version 2
  EXPECT_EQ(b.substr(20, 4), std::string("\x04\x03\x02\x01", 4));  // prim_id little-endian
  EXPECT_EQ(b.substr(44, 4), std::string("\x0d\x0c\x0b\x0a", 4));  // instance_id
  const float want[7] = {2.5f, 0, 0.25f, 0.5f, 0, -1, 0};
  for (int k : {0, 2, 3, 4, 5, 6}) {
    float f;
    std::memcpy(&f, b.data() + 16 + 4 * k, 4);
    EXPECT_EQ(bits(f), bits(want[k])) << "field " << k;
  }
}

TEST(HitFileBinary, Version1FilesAreStillReadWithoutInstances) {
  // A file written before instances: version 1, 28-byte records (no instance_id).
  TempDir tmp;
  const std::string path = tmp / "old.hits";
  std::string bytes = header("RPHT", 1, 2);
  const float f[7] = {2.5f, 0, 0.25f, 0.5f, 0, -1, 0};
  for (uint32_t prim : {7u, kInvalidId}) {
    std::string rec(28, '\0');
    std::memcpy(rec.data(), f, 28);
    std::memcpy(rec.data() + 4, &prim, 4);
    bytes += rec;
  }
  write_bytes(path, bytes);
  const std::vector<HitRecord> hits = read_hits(path);
  ASSERT_EQ(hits.size(), 2u);
  EXPECT_EQ(hits[0].prim_id, 7u);
  EXPECT_EQ(hits[0].t, 2.5f);
  EXPECT_EQ(hits[0].ng.y, -1.0f);
  EXPECT_EQ(hits[0].instance_id, kNoInstance);
  EXPECT_EQ(hits[1].prim_id, kInvalidId);
  EXPECT_EQ(hits[1].instance_id, kNoInstance);
  // And a CSV file without the instance_id column.
  const std::string csv = tmp / "old.csv";
  write_bytes(csv, "t,prim_id,u,v,ng_x,ng_y,ng_z\n2.5,7,0.25,0.5,0,-1,0\n");
  const std::vector<HitRecord> from_csv = read_hits(csv);
  ASSERT_EQ(from_csv.size(), 1u);
  EXPECT_EQ(from_csv[0].prim_id, 7u);
  EXPECT_EQ(from_csv[0].instance_id, kNoInstance);
}

TEST(RayFileCsv, RoundTripKeepsEveryBitButNanPayloads) {
  TempDir tmp;
  const std::string path = tmp / "rays.csv";
  for (const std::vector<Ray>& rays : {special_rays(), bit_pattern_rays(5000), std::vector<Ray>{}}) {
    write_rays(path, rays);
    const std::vector<Ray> back = read_rays(path);
    ASSERT_EQ(back.size(), rays.size());
    for (size_t i = 0; i < rays.size(); ++i) expect_csv_equal(bits(rays[i]), bits(back[i]), i);
  }
  EXPECT_EQ(tmp.entries(), std::set<std::string>{"rays.csv"});
}

TEST(RayFileCsv, WriterUsesTheHeaderAndPercentNineG) {
  TempDir tmp;
  const std::string path = tmp / "rays.csv";
  const float inf = std::numeric_limits<float>::infinity();
  write_rays(path, std::vector<Ray>{{{0, -0.0f, 1.5f}, 0, {1.0f / 3, -inf, from_bits(1)}, inf},
                                    {{from_bits(0xffc00001), 1e20f, -2}, 1e-3f, {0, 0, 1}, 100}});
  EXPECT_EQ(read_bytes(path),
            "ox,oy,oz,dx,dy,dz,tnear,tfar\n"
            "0,-0,1.5,0.333333343,-inf,1.40129846e-45,0,inf\n"
            "nan,1.00000002e+20,-2,0,0,1,0.00100000005,100\n");
}

TEST(RayFileCsv, ExtensionIsCaseInsensitive) {
  TempDir tmp;
  const std::vector<Ray> rays = {{{1, 2, 3}, 0, {0, 0, -1}, 10}};
  for (const char* name : {"A.CSV", "b.Csv", "c.csv"}) {
    write_rays(tmp / name, rays);
    EXPECT_EQ(read_bytes(tmp / name), "ox,oy,oz,dx,dy,dz,tnear,tfar\n1,2,3,0,0,-1,0,10\n") << name;
    EXPECT_EQ(bits(read_rays(tmp / name).at(0)), bits(rays[0])) << name;
  }
  for (const char* name : {"d.csv.bin", "e.RAYS", "csv"}) {
    write_rays(tmp / name, rays);
    EXPECT_EQ(read_bytes(tmp / name).substr(0, 4), "RPRY") << name;
  }
  // Any other extension names no format: refused on writing and reading, naming it.
  for (const char* name : {"e.txt", "f.json", "g.hits"}) {
    const std::string p = tmp / name, ext = fs::path(name).extension().string();
    const std::string want = p + ": unknown ray file extension '" + ext + "' (.csv for text; .bin, .rays or none for binary)";
    EXPECT_EQ(error_of([&] { write_rays(p, rays); }), want);
    EXPECT_EQ(error_of([&] { check_ray_file_name(p); }), want);
    write_bytes(p, "ox,oy,oz,dx,dy,dz\n");
    EXPECT_EQ(error_of([&] { read_rays(p); }), want);
  }
  EXPECT_EQ(error_of([&] { write_hits(tmp / "h.rays", {}); }),
            tmp / "h.rays" + ": unknown hit file extension '.rays' (.csv for text; .bin, .hits or none for binary)");
}

TEST(RayFileCsv, ReadsWhatNumpyAndSpreadsheetsWrite) {
  TempDir tmp;
  const std::string path = tmp / "np.csv";
  const float inf = std::numeric_limits<float>::infinity();
  // numpy.savetxt(..., delimiter=",", header=...): '# ' before the names, %.18e values.
  write_bytes(path,
              "# ox,oy,oz,dx,dy,dz,tnear,tfar\n"
              "1.000000000000000000e+00,2.000000000000000000e+00,3.000000000000000000e+00,0.000000000000000000e+00,"
              "0.000000000000000000e+00,-1.000000000000000000e+00,0.000000000000000000e+00,inf\n");
  std::vector<Ray> rays = read_rays(path);
  ASSERT_EQ(rays.size(), 1u);
  EXPECT_EQ(bits(rays[0]), bits(Ray{{1, 2, 3}, 0, {0, 0, -1}, inf}));
  // A spreadsheet: byte order mark, blanks after commas, columns in another order, CRLF; no
  // tnear or tfar (0 and inf).
  write_bytes(path, "\xEF\xBB\xBF dx, dy, dz, ox, oy, oz\r\n0, 0, -1, 1, 2, 3\r\n\t0 ,1,0 , 4,5,6\r\n");
  rays = read_rays(path);
  ASSERT_EQ(rays.size(), 2u);
  EXPECT_EQ(bits(rays[0]), bits(Ray{{1, 2, 3}, 0, {0, 0, -1}, inf}));
  EXPECT_EQ(bits(rays[1]), bits(Ray{{4, 5, 6}, 0, {0, 1, 0}, inf}));
  write_bytes(path, "tfar,ox,oy,oz,dx,dy,dz,tnear\n10,1,2,3,0,0,-1,0.5\n");
  EXPECT_EQ(bits(read_rays(path).at(0)), bits(Ray{{1, 2, 3}, 0.5f, {0, 0, -1}, 10}));
  // Hits: every column needed, any order.
  write_bytes(path, "#ng_x,ng_y,ng_z,t,u,v,prim_id\n0,1,0,2.5,0.25,0.5,7\n");
  const std::vector<HitRecord> hits = read_hits(path);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_EQ(hits[0].t, 2.5f);
  EXPECT_EQ(hits[0].prim_id, 7u);
  EXPECT_EQ(hits[0].u, 0.25f);
  EXPECT_EQ(hits[0].v, 0.5f);
  EXPECT_EQ(hits[0].ng, (Vec3f{0, 1, 0}));
}

TEST(RayFileCsv, AcceptsCrlfAndTrailingBlankLines) {
  TempDir tmp;
  const std::string path = tmp / "crlf.csv";
  write_bytes(path, "ox,oy,oz,dx,dy,dz,tnear,tfar\r\n1,2,3,4,5,6,0,inf\r\n-1,-2,-3,nan,-nan,-inf,0.5,1e-45\r\n\r\n\n");
  const std::vector<Ray> rays = read_rays(path);
  ASSERT_EQ(rays.size(), 2u);
  EXPECT_EQ(bits(rays[0]), bits(Ray{{1, 2, 3}, 0, {4, 5, 6}, std::numeric_limits<float>::infinity()}));
  EXPECT_EQ(rays[1].org, (Vec3f{-1, -2, -3}));
  EXPECT_TRUE(std::isnan(rays[1].dir.x));
  EXPECT_TRUE(std::isnan(rays[1].dir.y));
  EXPECT_EQ(rays[1].dir.z, -std::numeric_limits<float>::infinity());
  EXPECT_EQ(rays[1].tnear, 0.5f);
  EXPECT_EQ(bits(rays[1].tfar), 1u);
  // No newline at the end, and a header-only file, are fine too.
  write_bytes(path, "ox,oy,oz,dx,dy,dz,tnear,tfar\n1,2,3,4,5,6,0,1");
  EXPECT_EQ(read_rays(path).size(), 1u);
  write_bytes(path, "ox,oy,oz,dx,dy,dz,tnear,tfar");
  EXPECT_EQ(read_rays(path).size(), 0u);
}

// ---- parts of a file, as the ranks of an MPI run read them --------------------------------

/// The rays of every part of `path` for `count` parts, concatenated in part order.
std::vector<Ray> read_in_parts(const std::string& path, int count) {
  std::vector<Ray> all;
  for (int i = 0; i < count; ++i) {
    const std::vector<Ray> part = read_rays(path, FilePart{i, count});
    all.insert(all.end(), part.begin(), part.end());
  }
  return all;
}

TEST(RayFileParts, RecordRangesCoverTheBatchInWholePacketsOfEight) {
  for (uint64_t n : {0ull, 1ull, 7ull, 8ull, 9ull, 100ull, 4097ull, 1000003ull})
    for (int count = 1; count <= 7; ++count) {
      uint64_t next = 0;
      for (int i = 0; i < count; ++i) {
        const RecordRange r = part_records(n, {i, count});
        EXPECT_EQ(r.first, next) << n << " " << i << "/" << count;
        EXPECT_LE(r.first, r.last);
        if (i + 1 < count) {
          EXPECT_EQ(r.last % 8, 0u) << n << " " << i << "/" << count;
        }
        next = r.last;
      }
      EXPECT_EQ(next, n) << n << " in " << count;
    }
  // The bounds are n * index / count rounded down to a multiple of 8, without overflow.
  EXPECT_EQ(part_records(100, {1, 3}).first, 32u);
  EXPECT_EQ(part_records(100, {1, 3}).last, 64u);
  const uint64_t huge = uint64_t(1) << 62;
  EXPECT_EQ(part_records(huge, {1, 2}).first, huge / 2);
}

TEST(RayFileParts, PartsTogetherAreTheWholeFileInEitherFormat) {
  TempDir tmp;
  const std::vector<Ray> rays = bit_pattern_rays(5000);
  for (const std::string name : {"r.bin", "r.csv"}) {
    const std::string path = tmp / name;
    write_rays(path, rays);
    const std::vector<Ray> whole = read_rays(path);
    ASSERT_EQ(whole.size(), rays.size());
    for (int count : {1, 2, 3, 5, 64}) {
      const std::vector<Ray> parts = read_in_parts(path, count);
      ASSERT_EQ(parts.size(), whole.size()) << name << " in " << count;
      for (size_t i = 0; i < whole.size(); ++i) ASSERT_EQ(bits(parts[i]), bits(whole[i])) << name << " ray " << i;
    }
  }
  // CSV by bytes: CRLF, blank trailing lines, no newline at the end, and more parts than lines.
  const std::string path = tmp / "crlf.csv";
  write_bytes(path, "# ox, oy, oz, dx, dy, dz\r\n1,2,3,4,5,6\r\n7,8,9,1,2,3\r\n-1,-2,-3,4,5,6\r\n\r\n\n");
  for (int count : {1, 2, 3, 4, 9, 40}) {
    const std::vector<Ray> parts = read_in_parts(path, count);
    ASSERT_EQ(parts.size(), 3u) << count;
    EXPECT_EQ(parts[2].org, (Vec3f{-1, -2, -3})) << count;
  }
  write_bytes(path, "ox,oy,oz,dx,dy,dz\n1,2,3,4,5,6\n1,2,3,4,5,7");
  EXPECT_EQ(read_in_parts(path, 2).back().dir.z, 7.0f);
}

TEST(RayFileParts, TheLowestFailingPartGivesTheWholeReadsMessage) {
  TempDir tmp;
  const std::string p = tmp / "bad.csv";
  const std::string head = "ox,oy,oz,dx,dy,dz,tnear,tfar\n";
  std::string good;
  for (int i = 0; i < 40; ++i) good += "1,2,3,4,5,6,0,1\n";
  // Errors early, late and across the parts' boundaries: a bad value, a short line, a blank line
  // in one part followed by data in the next, and a bad line after a blank one.
  const std::vector<std::string> files = {
      head + good + "1,2,3,4,5,6,0,x\n" + good,       head + good + good + "1,2,3\n",
      head + good + "\n\n\n" + good,                    head + "1,2,3,4,5,6,0,1\n\n" + good + "1,2\n",
      head + good + good + good + "\n" + "1,2,3,4,5,6,0,1\n", head + "ox\n" + good};
  for (const std::string& text : files) {
    write_bytes(p, text);
    const std::string whole = error_of([&] { read_rays(p); });
    ASSERT_NE(whole, test::kNoError);
    for (int count : {2, 3, 4, 7}) {
      std::string first = test::kNoError;
      for (int i = 0; i < count && first == test::kNoError; ++i) first = error_of([&] { read_rays(p, FilePart{i, count}); });
      EXPECT_EQ(first, whole) << count << " parts";
    }
  }
  // A binary file's header and size are every part's to check.
  const std::string b = tmp / "bad.bin";
  write_bytes(b, header("RPRY", 1, 3) + std::string(32 * 2, '\0'));
  const std::string whole = error_of([&] { read_rays(b); });
  for (int i = 0; i < 3; ++i) EXPECT_EQ(error_of([&] { read_rays(b, FilePart{i, 3}); }), whole);
}

TEST(HitFileParts, HeadAndRecordsOfConsecutiveBatchesAreWhatWriteHitsWrites) {
  TempDir tmp;
  const std::vector<HitRecord> hits = special_hits();
  for (const std::string name : {"h.hits", "h.csv"}) {
    const std::string path = tmp / name;
    write_hits(path, hits);
    for (size_t cut : {size_t(0), size_t(1), hits.size() / 2, hits.size()}) {
      std::string bytes = hit_file_head(path, hits.size());
      append_hit_records(path, std::span(hits).first(cut), bytes);
      append_hit_records(path, std::span(hits).subspan(cut), bytes);
      EXPECT_EQ(bytes, read_bytes(path)) << name << " cut at " << cut;
    }
  }
}

TEST(HitFileCsv, RoundTripAndMissIsWrittenAsMinusOne) {
  TempDir tmp;
  const std::string path = tmp / "hits.csv";
  const std::vector<HitRecord> hits = special_hits();
  write_hits(path, hits);
  const std::vector<HitRecord> back = read_hits(path);
  ASSERT_EQ(back.size(), hits.size());
  for (size_t i = 0; i < hits.size(); ++i) {
    const auto w = bits(hits[i]), g = bits(back[i]);
    EXPECT_EQ(w[1], g[1]) << "hit " << i << " prim_id";
    EXPECT_EQ(w[7], g[7]) << "hit " << i << " instance_id";
    for (size_t k : {0, 2, 3, 4, 5, 6}) {
      if (std::isnan(from_bits(w[k])))
        EXPECT_TRUE(std::isnan(from_bits(g[k]))) << "hit " << i << " field " << k;
      else
        EXPECT_EQ(w[k], g[k]) << "hit " << i << " field " << k;
    }
  }
  write_hits(path, std::vector<HitRecord>{HitRecord{}, {2.5f, 7, 0.25f, 0.5f, {0, 0, 1}, 3},
                                          {1, 4294967294u, 0, 1, {-0.0f, 1, 0}}});
  EXPECT_EQ(read_bytes(path),
            "t,prim_id,u,v,ng_x,ng_y,ng_z,instance_id\n"
            "inf,-1,0,0,0,0,0,-1\n"
            "2.5,7,0.25,0.5,0,0,1,3\n"
            "1,4294967294,0,1,-0,1,0,-1\n");
  const std::vector<HitRecord> three = read_hits(path);
  ASSERT_EQ(three.size(), 3u);
  EXPECT_EQ(bits(three[0]), bits(HitRecord{}));
  EXPECT_EQ(three[2].prim_id, 4294967294u);
  EXPECT_EQ(bits(three[2].ng.x), 0x80000000u);
  EXPECT_EQ(tmp.entries(), std::set<std::string>{"hits.csv"});
}

TEST(RayFileErrors, MissingFileOrDirectoryCannotBeOpened) {
  TempDir tmp;
  for (const char* name : {"missing.bin", "missing.csv"}) {
    const std::string p = tmp / name;
    EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": cannot open: No such file or directory");
    EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": cannot open: No such file or directory");
  }
  fs::create_directory(tmp / "dir.csv");
  EXPECT_EQ(error_of([&] { read_rays(tmp / "dir.csv"); }), tmp / "dir.csv" + ": cannot read: not a regular file (a directory)");
  EXPECT_EQ(error_of([&] { read_hits(tmp.dir.string()); }), tmp.dir.string() + ": cannot read: not a regular file (a directory)");
}

TEST(RayFileErrors, WrongMagicIsNamedWithNonPrintablesAsQuestionMarks) {
  TempDir tmp;
  const std::string p = tmp / "x.bin";
  write_bytes(p, std::string("AB\x01\xff", 4) + std::string(60, '\0'));
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": not a raypack ray file (magic 'AB?\?', expected 'RPRY')");
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": not a raypack hit file (magic 'AB?\?', expected 'RPHT')");
  // A CSV file under a binary name is caught by its magic too.
  write_bytes(p, "ox,oy,oz,dx,dy,dz,tnear,tfar\n1,2,3,4,5,6,0,1\n");
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": not a raypack ray file (magic 'ox,o', expected 'RPRY')");
}

TEST(RayFileErrors, RayAndHitFilesAreToldApart) {
  TempDir tmp;
  const std::string rays = tmp / "rays.bin", hits = tmp / "hits.bin";
  write_rays(rays, std::vector<Ray>(2));
  write_hits(hits, std::vector<HitRecord>(2));
  EXPECT_EQ(error_of([&] { read_hits(rays); }), rays + ": not a raypack hit file (magic 'RPRY', expected 'RPHT')");
  EXPECT_EQ(error_of([&] { read_rays(hits); }), hits + ": not a raypack ray file (magic 'RPHT', expected 'RPRY')");
}

TEST(RayFileErrors, UnsupportedVersion) {
  TempDir tmp;
  const std::string p = tmp / "v7.bin";
  write_bytes(p, header("RPRY", 7, 0));
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": unsupported version 7 (1)");
  write_bytes(p, header("RPHT", 0, 0));
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": unsupported version 0 (1 or 2)");
  write_bytes(p, header("RPHT", 3, 0));
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": unsupported version 3 (1 or 2)");
}

TEST(RayFileErrors, FileShorterThanTheHeader) {
  TempDir tmp;
  const std::string p = tmp / "short.bin";
  write_bytes(p, header("RPRY", 1, 0).substr(0, 9));
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": truncated: 9 bytes, the header needs 16");
  write_bytes(p, header("RPHT", 1, 0).substr(0, 15));
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": truncated: 15 bytes, the header needs 16");
  write_bytes(p, "RP");
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": truncated: 2 bytes, the header needs 16");
  write_bytes(p, "");
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": truncated: 0 bytes, the header needs 16");
}

TEST(RayFileErrors, AbsurdCountIsRejectedBeforeAllocating) {
  TempDir tmp;
  const std::string p = tmp / "absurd.bin";
  const auto start = std::chrono::steady_clock::now();
  write_bytes(p, header("RPRY", 1, 4000000000u) + std::string(64, '\0'));
  EXPECT_EQ(error_of([&] { read_rays(p); }),
            p + ": the header declares 4000000000 rays (128000000000 bytes) but 64 bytes follow it");
  write_bytes(p, header("RPRY", 1, uint64_t(1) << 63) + std::string(64, '\0'));
  EXPECT_EQ(error_of([&] { read_rays(p); }),
            p + ": the header declares 9223372036854775808 rays (295147905179352825856 bytes) but 64 bytes follow it");
  write_bytes(p, header("RPHT", 1, UINT64_MAX));
  EXPECT_EQ(error_of([&] { read_hits(p); }),
            p + ": the header declares 18446744073709551615 hits (516508834063867445220 bytes) but 0 bytes follow it");
  // Allocating 128 GB (or failing to) would not be this quick; under ASan it would abort.
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
}

TEST(RayFileErrors, TruncatedDataAndTrailingBytes) {
  TempDir tmp;
  const std::string p = tmp / "data.bin";
  write_bytes(p, header("RPRY", 1, 3) + std::string(80, '\0'));
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": the header declares 3 rays (96 bytes) but 80 bytes follow it");
  write_bytes(p, header("RPRY", 1, 1) + std::string(33, '\0'));
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": the header declares 1 ray (32 bytes) but 33 bytes follow it");
  write_bytes(p, header("RPRY", 1, 0) + "x");
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": the header declares 0 rays (0 bytes) but 1 bytes follow it");
  write_bytes(p, header("RPHT", 1, 2) + std::string(57, '\0'));
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": the header declares 2 hits (56 bytes) but 57 bytes follow it");
  write_bytes(p, header("RPHT", 1, 2) + std::string(55, '\0'));
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": the header declares 2 hits (56 bytes) but 55 bytes follow it");
  write_bytes(p, header("RPHT", 2, 2) + std::string(56, '\0'));  // version 2: 32-byte records
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": the header declares 2 hits (64 bytes) but 56 bytes follow it");
}

TEST(RayFileErrors, CsvHeaderMustNameTheColumns) {
  TempDir tmp;
  const std::string p = tmp / "h.csv";
  const std::string rays = "ox,oy,oz,dx,dy,dz,tnear,tfar", hits = "t,prim_id,u,v,ng_x,ng_y,ng_z,instance_id";
  const std::pair<std::string, std::string> cases[] = {
      {"", "empty file: expected a header naming the columns"},
      {"\n", "expected a header naming the columns (" + rays + ")"},
      {"1,2,3,4,5,6,0,1\n", "expected a header naming the columns (" + rays + ")"},
      {"OX,OY,OZ,DX,DY,DZ\n", "expected a header naming the columns (" + rays + ")"},
      {"ox,oy,oz,dx,dy,dz,t\n", "unknown column 't' (columns: " + rays + ")"},
      {"ox,oy,oz,dx,dy,dz,,\n", "unknown column '' (columns: " + rays + ")"},
      {"ox,oy,oz,dx,dy,ox\n", "column 'ox' appears twice"},
      {"ox,oy,oz,dx,dy,tnear,tfar\n",
       "no column 'dz' (columns: " + rays + "; all but tnear and the ones after it are needed)"}};
  for (const auto& [text, why] : cases) {
    write_bytes(p, text);
    EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 1: " + why) << text;
  }
  write_rays(p, std::vector<Ray>(1));
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": line 1: expected a header naming the columns (" + hits + ")");
  write_bytes(p, "t,prim_id,u,v,ng_x,ng_y\n");
  EXPECT_EQ(error_of([&] { read_hits(p); }),
            p + ": line 1: no column 'ng_z' (columns: " + hits + "; all but instance_id are needed)");
}

TEST(RayFileErrors, CsvWrongValueCounts) {
  TempDir tmp;
  const std::string p = tmp / "n.csv";
  const std::string head = "ox,oy,oz,dx,dy,dz,tnear,tfar\n", good = "1,2,3,4,5,6,0,1\n";
  write_bytes(p, head + good + good + good + "1,2,3,4,5,6,0\n" + good);
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 5: 7 values, expected 8");
  write_bytes(p, head + "1,2,3,4,5,6,0,1,\n");
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 2: 9 values, expected 8");
  write_bytes(p, head + good + "42\r\n");
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 3: 1 value, expected 8");
  write_bytes(p, "t,prim_id,u,v,ng_x,ng_y,ng_z\ninf,-1,0,0,0,0,0,0\n");
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": line 2: 8 values, expected 7");
  // A blank line is only fine at the end.
  write_bytes(p, head + good + "\n" + good);
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 3: blank line before the end of the data");
}

TEST(RayFileErrors, CsvNonNumbers) {
  TempDir tmp;
  const std::string p = tmp / "nn.csv";
  const std::string head = "ox,oy,oz,dx,dy,dz,tnear,tfar\n", good = "1,2,3,4,5,6,0,1\n";
  write_bytes(p, head + good + "1,2,abc,4,5,6,0,1\n");
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 3: 'abc' is not a number");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"1,,3,4,5,6,0,1", "''"},      {"1,2,3,4,5,6,0, ", "''"}, {"+1,2,3,4,5,6,0,1", "'+1'"},
      {"1,2,3,4,5,6,0,1e", "'1e'"},  {"1,2,3,0x10,5,6,0,1", "'0x10'"},
      {"1,2,3,4,5,6,0,1\v", "'1?'"}, {"1,2,3,4,5,6,0,\"1\"", "'\"1\"'"}, {"1,2,3,4,5,6,0,1 2", "'1 2'"},
      {"1,2,3,4,5,6,0," + std::string(40, 'z'), "'" + std::string(32, 'z') + "...'"}};
  for (const auto& [line, shown] : cases) {
    write_bytes(p, head + line + "\n");
    EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 2: " + shown + " is not a number") << line;
  }
  write_bytes(p, head + "1,2,3,4,5,6,0,1e50\n");
  EXPECT_EQ(error_of([&] { read_rays(p); }), p + ": line 2: '1e50' is out of the float32 range");
  write_bytes(p, "t,prim_id,u,v,ng_x,ng_y,ng_z\n1,0,0,0,0,0,1\n1,0,q,0,0,0,1\n");
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": line 3: 'q' is not a number");
}

TEST(RayFileErrors, CsvPrimitiveIdMustBeAnIntegerFromMinusOneToTwoToTheThirtyTwoMinusTwo) {
  TempDir tmp;
  const std::string p = tmp / "ids.csv";
  const std::string head = "t,prim_id,u,v,ng_x,ng_y,ng_z\n", good = "1,3,0,0,0,0,1\n";
  write_bytes(p, head + good + good + "1,x,0,0,0,0,1\n");
  EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": line 4: 'x' is not a primitive id");
  for (const char* id : {"4294967295", "-2", "1.5", "", "1e3", "+1", "99999999999999999999", "inf"}) {
    write_bytes(p, head + "1," + id + ",0,0,0,0,1\n");
    EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": line 2: '" + id + "' is not a primitive id") << id;
  }
  write_bytes(p, head + "1,4294967294,0,0,0,0,1\ninf,-1,0,0,0,0,0\n2,0,0,0,0,0,1\n");
  const std::vector<HitRecord> hits = read_hits(p);
  ASSERT_EQ(hits.size(), 3u);
  EXPECT_EQ(hits[0].prim_id, 4294967294u);
  EXPECT_EQ(hits[1].prim_id, kInvalidId);
  EXPECT_EQ(hits[2].prim_id, 0u);
  // instance_id follows the same rule.
  const std::string with_instance = "t,prim_id,u,v,ng_x,ng_y,ng_z,instance_id\n";
  for (const char* id : {"4294967295", "-2", "1.5", "", "x"}) {
    write_bytes(p, with_instance + "1,3,0,0,0,0,1," + id + "\n");
    EXPECT_EQ(error_of([&] { read_hits(p); }), p + ": line 2: '" + id + "' is not an instance id") << id;
  }
  write_bytes(p, with_instance + "1,3,0,0,0,0,1,4294967294\ninf,-1,0,0,0,0,0,-1\n");
  const std::vector<HitRecord> placed = read_hits(p);
  ASSERT_EQ(placed.size(), 2u);
  EXPECT_EQ(placed[0].instance_id, 4294967294u);
  EXPECT_EQ(placed[1].instance_id, kNoInstance);
}

TEST(RayFileWrite, MissingDirectoryGivesTheWriteErrorAndLeavesNoFile) {
  TempDir tmp;
  for (const char* name : {"rays.bin", "rays.csv"}) {
    const std::string p = tmp / (std::string("no-such-dir/") + name);
    EXPECT_EQ(error_of([&] { write_rays(p, std::vector<Ray>(3)); }), p + ": cannot write: No such file or directory");
    EXPECT_EQ(error_of([&] { write_hits(p, std::vector<HitRecord>(3)); }),
              p + ": cannot write: No such file or directory");
  }
  EXPECT_TRUE(tmp.entries().empty());
  // A parent that is a file, not a directory.
  write_bytes(tmp / "file", "x");
  const std::string p = tmp / "file/rays.bin";
  EXPECT_EQ(error_of([&] { write_rays(p, std::vector<Ray>(3)); }), p + ": cannot write: Not a directory");
  EXPECT_EQ(tmp.entries(), std::set<std::string>{"file"});
}

/// The error of writing rays to `path` in a child process that has dropped root's rights
/// first (to the user and group nobody, 65534), if it had them: root writes into any
/// directory, so the refusal can only be seen without them.
std::string write_error_without_root(const std::string& path) {
  int fds[2];
  if (::pipe(fds) != 0) return "pipe failed";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    std::string message;
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) message = "cannot drop root's rights";
    else message = error_of([&] { write_rays(path, std::vector<Ray>(3)); });
    const ssize_t written = ::write(fds[1], message.data(), message.size());
    ::_exit(written == ssize_t(message.size()) ? 0 : 1);
  }
  ::close(fds[1]);
  std::string message;
  char buffer[256];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;) message.append(buffer, size_t(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return message;
}

TEST(RayFileWrite, UnwritableDirectoryGivesTheWriteErrorAndLeavesNoFile) {
  TempDir tmp;
  fs::create_directory(tmp / "ro");
  // Others (the unprivileged child) may enter the folders but not write into "ro".
  fs::permissions(tmp.dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                               fs::perms::others_read | fs::perms::others_exec);
  fs::permissions(tmp / "ro", fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                  fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  const std::string p = tmp / "ro/rays.bin";
  EXPECT_EQ(write_error_without_root(p), p + ": cannot write: Permission denied");
  fs::permissions(tmp / "ro", fs::perms::owner_all);
  EXPECT_TRUE(fs::is_empty(tmp / "ro"));
}

TEST(RayFileWrite, ADirectoryTargetIsRefusedAndNothingIsLeft) {
  TempDir tmp;
  fs::create_directory(tmp / "taken.bin");
  fs::create_directory(tmp / "taken.csv");
  EXPECT_EQ(error_of([&] { write_rays(tmp / "taken.bin", std::vector<Ray>(3)); }),
            tmp / "taken.bin" + ": cannot write: it is a directory");
  EXPECT_EQ(error_of([&] { write_hits(tmp / "taken.csv", std::vector<HitRecord>(3)); }),
            tmp / "taken.csv" + ": cannot write: it is a directory");
  EXPECT_EQ(tmp.entries(), (std::set<std::string>{"taken.bin", "taken.csv"}));
  EXPECT_TRUE(fs::is_directory(tmp / "taken.bin"));
}

TEST(RayFileWrite, RewriteReplacesTheWholeFile) {
  TempDir tmp;
  const std::string p = tmp / "r.csv";
  write_rays(p, bit_pattern_rays(100));
  write_rays(p, std::vector<Ray>{{{1, 2, 3}, 0, {4, 5, 6}, 7}});
  EXPECT_EQ(read_bytes(p), "ox,oy,oz,dx,dy,dz,tnear,tfar\n1,2,3,4,5,6,0,7\n");
  const std::string b = tmp / "r.bin";
  write_rays(b, bit_pattern_rays(100));
  write_rays(b, std::vector<Ray>(1));
  EXPECT_EQ(fs::file_size(b), 48u);
  EXPECT_EQ(tmp.entries(), (std::set<std::string>{"r.csv", "r.bin"}));
}

}  // namespace
}  // namespace rp
