// The kernel cache's key text and entry files (jit/kernel_cache.h).
#include "jit/kernel_cache.h"

#include "jit/device_program.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <unordered_map>
#include <vector>

namespace simit::jit {

namespace {

// ---------------------------------------------------------------------------
// The key text

class KeyWriter {
 public:
  std::string out;

  void num(int64_t v) {
    out += std::to_string(v);
    out += ' ';
  }
  void bits(double f) {  // exact: -0.0, NaN payloads and the last bit all differ
    uint64_t u;
    std::memcpy(&u, &f, sizeof u);
    char buf[20];
    std::snprintf(buf, sizeof buf, "%llx ", static_cast<unsigned long long>(u));
    out += buf;
  }
  void tag(const char* t) {
    out += t;
    out += ' ';
  }

  void expr(const ExprRef& e) {
    if (!e) {
      tag("-");
      return;
    }
    auto [it, fresh] = ids_.emplace(e.get(), static_cast<int>(ids_.size()));
    if (!fresh) {
      out += '#';
      num(it->second);
      return;
    }
    out += '(';
    num(static_cast<int>(e->kind));
    num(static_cast<int>(e->ty));
    num(e->op);
    num(e->slot);
    num(e->comp);
    bits(e->f);
    num(e->i);
    num(e->loose);
    num(static_cast<int64_t>(e->ops.size()));
    for (const ExprRef& o : e->ops) expr(o);
    out += ") ";
  }

  void block(const std::vector<Stmt>& body) {
    out += "{ ";
    for (const Stmt& s : body) stmt(s);
    out += "} ";
  }

  void stmt(const Stmt& s) {
    out += '[';
    num(static_cast<int>(s.kind));
    num(s.slot);
    num(s.comp);
    num(s.pair);
    num(s.member);
    num(s.error);
    num(s.fn);
    num(s.n);
    expr(s.index);
    expr(s.value);
    num(static_cast<int64_t>(s.args.size()));
    for (const ExprRef& a : s.args) expr(a);
    num(static_cast<int64_t>(s.outs.size()));
    for (int o : s.outs) num(o);
    block(s.body);
    block(s.orelse);
    out += "]\n";
  }

  void arrays(const std::vector<ArraySlot>& slots) {
    tag("arrays");
    num(static_cast<int64_t>(slots.size()));
    for (const ArraySlot& a : slots) {
      num(static_cast<int>(a.kind));
      num(a.member);
      num(a.index);
      num(static_cast<int>(a.ty));
      num(a.single);
      num(a.written);
      num(a.components);
      num(static_cast<int64_t>(a.reads.size()));
      for (const auto& [row, col] : a.reads) {
        num(row);
        num(col);
      }
    }
    out += '\n';
  }

  void types(const char* what, const std::vector<Ty>& ts) {
    tag(what);
    num(static_cast<int64_t>(ts.size()));
    for (Ty t : ts) num(static_cast<int>(t));
    out += '\n';
  }

  void ops(const char* what, const std::vector<VectorOp>& list) {
    tag(what);
    num(static_cast<int64_t>(list.size()));
    for (const VectorOp& op : list) {
      num(static_cast<int>(op.kind));
      num(op.length);
      num(op.row_ptr);
      num(op.cols);
      num(op.values);
      num(op.rows);
      num(op.x);
      num(op.y);
      num(op.block);
      num(op.group);
      num(op.guard);
      num(static_cast<int64_t>(op.sums.size()));
      for (int s : op.sums) num(s);
      block(op.body);
    }
    out += '\n';
  }

 private:
  std::unordered_map<const Expr*, int> ids_;
};

// ---------------------------------------------------------------------------
// The entry files

constexpr char kMagic[8] = {'S', 'I', 'M', 'I', 'T', 'K', 'O', '\0'};
// The file's layout (bump when it changes; what the object holds is kKernelFormatVersion's).
// Version 2 added the report (CacheEntry::simd).
constexpr uint32_t kFileVersion = 2;
// magic, version, symbol length, object length, checksum, digest, report length.
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 8 + KernelCache::kDigestBytes + 4;
// A symbol is a short generated name; an object above this is not one of ours.
constexpr uint32_t kMaxSymbol = 1024;
constexpr uint64_t kMaxObject = uint64_t{1} << 30;
constexpr uint32_t kMaxReport = 1 << 20;

void put_le(std::string& s, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) s += static_cast<char>((v >> (8 * i)) & 0xff);
}
uint64_t get_le(const char* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t{static_cast<unsigned char>(p[i])} << (8 * i);
  return v;
}

uint64_t checksum(const CacheEntry& e) {
  return fnv1a64(e.object.data(), e.object.size(),
                 fnv1a64(e.simd.data(), e.simd.size(), fnv1a64(e.symbol.data(), e.symbol.size())));
}

// A report's words as one field of a line: no tabs or line breaks.
std::string field(std::string s) {
  std::replace_if(
      s.begin(), s.end(), [](char c) { return c == '\t' || c == '\n'; }, ' ');
  return s;
}

// The tab-separated fields of a line.
std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> out(1);
  for (char c : line) {
    if (c == '\t')
      out.emplace_back();
    else
      out.back() += c;
  }
  return out;
}

// A whole decimal number in [lo, hi], or false.
bool whole(const std::string& s, int lo, int hi, int& out) {
  if (s.empty() || s.size() > 9) return false;
  int v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + (c - '0');
  }
  if (v < lo || v > hi) return false;
  out = v;
  return true;
}

// A name no other writer picks: this process, a counter, and random bits (for processes of
// the same id on machines sharing the folder).
std::string temporary_name(const std::string& final_name) {
  static std::atomic<uint64_t> counter{0};
  static const uint64_t salt = [] {
    std::random_device rd;
    return (uint64_t{rd()} << 32) ^ rd();
  }();
  char buf[64];
  std::snprintf(buf, sizeof buf, ".tmp.%ld.%llu.%016llx", static_cast<long>(::getpid()),
                static_cast<unsigned long long>(counter++), static_cast<unsigned long long>(salt));
  return final_name + buf;
}

bool write_all(int fd, const std::string& data) {
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

std::string kernel_key_text(const Trace& t) {
  KeyWriter w;
  w.tag("map");
  w.num(t.arity);
  w.num(t.reduce);
  w.num(t.writes_fields);
  w.num(t.float32);
  w.num(t.deferred);
  w.num(static_cast<int64_t>(t.errors.size()));
  w.out += '\n';
  w.arrays(t.arrays);
  w.types("scalars", t.scalars);
  w.types("locals", t.locals);
  w.tag("mutable");
  for (bool m : t.local_mutable) w.num(m);
  w.tag("\npairs");
  for (int p : t.pairs) w.num(p);
  w.tag("\nscratch");
  for (int s : t.scratch) w.num(s);
  w.out += "\nbody\n";
  w.block(t.body);
  return std::move(w.out);
}

std::string kernel_key_text(const SystemTrace& t) {
  KeyWriter w;
  w.tag("system");
  w.num(t.scalars);
  w.num(static_cast<int64_t>(t.sizes.size()));
  w.num(t.matrices_in_place);
  w.num(t.device);
  w.num(t.float32);
  w.num(static_cast<int64_t>(t.errors.size()));
  w.out += '\n';
  w.arrays(t.arrays);
  w.types("locals", t.locals);
  w.ops("before", t.before);
  w.tag("while");
  w.expr(t.condition);
  w.out += '\n';
  w.ops("body", t.body);
  w.ops("after", t.after);
  // A device program's code is its steps, numbered as the plan lays them out: a plan that
  // lays them out otherwise must not load this code (a step's number would name another).
  if (t.device) {
    w.tag("\nsteps");
    const DeviceProgram p = plan_device_program(t);
    for (const DeviceStep* s : p.all()) {
      w.num(static_cast<int64_t>(s->kind));
      for (const DeviceStep& part : s->parts) w.num(100 + static_cast<int64_t>(part.kind));
    }
  }
  return std::move(w.out);
}

// The report as lines of tab-separated fields: "simd", map, lanes, vectorisers, SLP groups,
// why not in lanes; then one "loop" line per loop: number, width, interleave, what, why not.
std::string simd_report_text(const SimdReport& r) {
  std::string out = "simd\t" + std::to_string(r.map) + "\t" + std::to_string(r.lanes) + "\t" +
                    std::to_string(r.vectorisers) + "\t" + std::to_string(r.slp_groups) + "\t" +
                    field(r.lanes_why_not) + "\n";
  for (const SimdLoop& l : r.loops)
    out += "loop\t" + std::to_string(l.number) + "\t" + std::to_string(l.width) + "\t" +
           std::to_string(l.interleave) + "\t" + field(l.what) + "\t" + field(l.why_not) + "\n";
  return out;
}

bool read_simd_report(const std::string& text, SimdReport& r) {
  constexpr int kMost = 1 << 24;
  SimdReport out;
  size_t at = 0;
  bool head = false;
  while (at < text.size()) {
    const size_t end = text.find('\n', at);
    if (end == std::string::npos) return false;  // every line ends with a line break
    const std::vector<std::string> f = fields_of(text.substr(at, end - at));
    at = end + 1;
    int map = 0, vectorisers = 0;
    if (!head) {
      if (f.size() != 6 || f[0] != "simd" || !whole(f[1], 0, 1, map) ||
          !whole(f[2], 1, kMost, out.lanes) || !whole(f[3], 0, 1, vectorisers) ||
          !whole(f[4], 0, kMost, out.slp_groups))
        return false;
      out.reported = true;
      out.map = map != 0;
      out.vectorisers = vectorisers != 0;
      out.lanes_why_not = f[5];
      head = true;
      continue;
    }
    SimdLoop l;
    if (f.size() != 6 || f[0] != "loop" || !whole(f[1], 1, kMost, l.number) ||
        !whole(f[2], 1, kMost, l.width) || !whole(f[3], 1, kMost, l.interleave))
      return false;
    l.what = f[4];
    l.why_not = f[5];
    out.loops.push_back(std::move(l));
  }
  if (!head) return false;
  r = std::move(out);
  return true;
}

std::string hex_of(const std::string& bytes) {
  static const char* const digits = "0123456789abcdef";
  std::string s;
  s.reserve(bytes.size() * 2);
  for (unsigned char c : bytes) {
    s += digits[c >> 4];
    s += digits[c & 15];
  }
  return s;
}

uint64_t fnv1a64(const char* data, size_t size, uint64_t seed) {
  uint64_t h = seed;
  for (size_t i = 0; i < size; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string KernelCache::path_of(const std::string& digest) const {
  return (std::filesystem::path(folder_) / (hex_of(digest) + ".o")).string();
}

std::optional<CacheEntry> KernelCache::load(const std::string& digest) const {
  if (!enabled() || digest.size() != kDigestBytes) return std::nullopt;
  std::ifstream in(path_of(digest), std::ios::binary);
  if (!in) return std::nullopt;
  char h[kHeaderBytes];
  if (!in.read(h, sizeof h)) return std::nullopt;
  if (std::memcmp(h, kMagic, sizeof kMagic) != 0 || get_le(h + 8, 4) != kFileVersion)
    return std::nullopt;
  const uint64_t symbol_size = get_le(h + 12, 4), object_size = get_le(h + 16, 8);
  const uint64_t sum = get_le(h + 24, 8);
  const uint64_t report_size = get_le(h + 32 + kDigestBytes, 4);
  if (std::memcmp(h + 32, digest.data(), kDigestBytes) != 0) return std::nullopt;
  if (symbol_size == 0 || symbol_size > kMaxSymbol || object_size > kMaxObject ||
      report_size > kMaxReport)
    return std::nullopt;
  CacheEntry e;
  e.symbol.resize(symbol_size);
  e.simd.resize(report_size);
  e.object.resize(object_size);
  if (!in.read(e.symbol.data(), static_cast<std::streamsize>(symbol_size)) ||
      !in.read(e.simd.data(), static_cast<std::streamsize>(report_size)) ||
      !in.read(e.object.data(), static_cast<std::streamsize>(object_size)))
    return std::nullopt;                                                // truncated
  if (in.peek() != std::char_traits<char>::eof()) return std::nullopt;  // trailing bytes
  if (checksum(e) != sum) return std::nullopt;
  // Marks the entry used (its modification time: prune removes the least recently used).
  std::error_code ec;
  std::filesystem::last_write_time(path_of(digest), std::filesystem::file_time_type::clock::now(),
                                   ec);
  return e;
}

bool KernelCache::store(const std::string& digest, const CacheEntry& entry,
                        std::string& error) const {
  if (!enabled()) return true;
  if (digest.size() != kDigestBytes || entry.symbol.empty() || entry.symbol.size() > kMaxSymbol ||
      entry.object.size() > kMaxObject || entry.simd.size() > kMaxReport) {
    error = "not a kernel cache entry";
    return false;
  }
  std::error_code ec;
  std::filesystem::create_directories(folder_, ec);
  if (ec) {
    error = "cannot create " + folder_ + ": " + ec.message();
    return false;
  }
  std::string data(kMagic, sizeof kMagic);
  put_le(data, kFileVersion, 4);
  put_le(data, entry.symbol.size(), 4);
  put_le(data, entry.object.size(), 8);
  put_le(data, checksum(entry), 8);
  data += digest;
  put_le(data, entry.simd.size(), 4);
  data += entry.symbol;
  data += entry.simd;
  data += entry.object;

  const std::string final_name = path_of(digest), temp = temporary_name(final_name);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    error = "cannot create " + temp + ": " + std::strerror(errno);
    return false;
  }
  const bool written = write_all(fd, data);
  const int write_errno = errno;
  // No fsync: a file a crash left short fails its checks and is compiled again.
  const bool closed = ::close(fd) == 0;
  if (!written || !closed) {
    error = "cannot write " + temp + ": " + std::strerror(written ? errno : write_errno);
    ::unlink(temp.c_str());
    return false;
  }
  if (::rename(temp.c_str(), final_name.c_str()) != 0) {
    error = "cannot rename " + temp + ": " + std::strerror(errno);
    ::unlink(temp.c_str());
    return false;
  }
  prune(kKernelCacheMaxBytes);
  return true;
}

int KernelCache::prune(uint64_t max_bytes) const {
  namespace fs = std::filesystem;
  if (!enabled()) return 0;
  struct File {
    fs::path path;
    fs::file_time_type used;
    uint64_t bytes;
  };
  std::vector<File> entries;
  uint64_t total = 0;
  const auto now = fs::file_time_type::clock::now();
  std::error_code ec;
  for (fs::directory_iterator it(folder_, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code e;
    const fs::path& p = it->path();
    const std::string name = p.filename().string();
    const auto used = fs::last_write_time(p, e);
    const uint64_t bytes = e ? 0 : fs::file_size(p, e);
    if (e) continue;  // removed meanwhile (another run's prune)
    if (name.find(".o.tmp.") != std::string::npos) {
      if (now - used > std::chrono::hours(1)) fs::remove(p, e);
    } else if (name.size() == 2 * kDigestBytes + 2 && p.extension() == ".o") {
      entries.push_back({p, used, bytes});
      total += bytes;
    }
  }
  if (total <= max_bytes) return 0;
  std::sort(entries.begin(), entries.end(),
            [](const File& a, const File& b) { return a.used < b.used; });
  int removed = 0;
  for (const File& f : entries) {
    if (total <= max_bytes / 4 * 3) break;
    std::error_code e;
    if (fs::remove(f.path, e)) ++removed;
    total -= f.bytes;
  }
  return removed;
}

}  // namespace simit::jit
