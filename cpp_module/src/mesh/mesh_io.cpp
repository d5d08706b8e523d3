// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/mesh/mesh_io.h"

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string_view>
#include <vector>

#include "bsptet/numerics/errors.h"

namespace bsptet {

namespace {

std::string slurp(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(ErrorCode::kBadArgument, "read", -1, path + ": cannot open the file");
  std::string text;
  char buf[1 << 16];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw InputError(ErrorCode::kBadArgument, "read", -1, path + ": cannot read the file");
  return text;
}

// The C locale's white space (std::isspace without the locale lookup).
inline bool is_space(char c) { return c == ' ' || c == '\n' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Whitespace tokenizer that skips '#' comments and knows the line of each token.
class Tokens {
 public:
  Tokens(const std::string& text, std::string name) : text_(text), name_(std::move(name)) {}
  bool next(std::string_view& tok) {
    for (;;) {
      while (pos_ < text_.size() && is_space(text_[pos_])) {
        if (text_[pos_] == '\n') ++line_;
        ++pos_;
      }
      if (pos_ < text_.size() && text_[pos_] == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
        continue;
      }
      break;
    }
    if (pos_ >= text_.size()) return false;
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_]) && text_[pos_] != '#')
      ++pos_;
    tok = std::string_view(text_).substr(start, pos_ - start);
    return true;
  }
  std::string where() const { return name_ + ":" + std::to_string(line_); }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(ErrorCode::kBadArgument, "read", -1, where() + ": " + what);
  }
  std::string_view need(const char* what) {
    std::string_view t;
    if (!next(t)) fail(std::string("the file ends where ") + what + " was expected");
    return t;
  }
  // Numbers as strtoll / strtod read them (from_chars first: no copy, no locale; strtod for what
  // it does not take, such as a leading '+' or hexadecimal floats).
  long long integer(const char* what) {
    const std::string_view t = need(what);
    long long v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec == std::errc() && end == t.data() + t.size()) return v;
    const std::string copy(t);
    char* stop = nullptr;
    v = std::strtoll(copy.c_str(), &stop, 10);
    if (stop == copy.c_str() || *stop != '\0') fail(std::string("expected ") + what + ", found '" + copy + "'");
    return v;
  }
  double real(const char* what) {
    const std::string_view t = need(what);
    double v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size()) {
      const std::string copy(t);
      char* stop = nullptr;
      v = std::strtod(copy.c_str(), &stop);
      if (stop == copy.c_str() || *stop != '\0') fail(std::string("expected ") + what + ", found '" + copy + "'");
    }
    if (!std::isfinite(v)) fail(std::string("non-finite ") + what + " '" + std::string(t) + "'");
    return v;
  }
  void skip_rest_of_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  }

 private:
  const std::string& text_;
  std::string name_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

SurfaceMesh parse_off(const std::string& text, const std::string& name) {
  Tokens tk(text, name);
  const std::string_view head = tk.need("the OFF header");
  if (head != "OFF") tk.fail("not an OFF file (first word '" + std::string(head.substr(0, 20)) + "')");
  const long long nv = tk.integer("the vertex count"), nf = tk.integer("the face count");
  tk.integer("the edge count");
  if (nv < 0 || nf < 0 || nv > INT32_MAX || nf > INT32_MAX) tk.fail("invalid vertex or face count");
  SurfaceMesh s;
  // The counts come from the file: reserve no more than its text can hold (a vertex takes at least
  // three numbers of two characters each), so a lying header cannot exhaust memory.
  s.xyz.reserve(std::min(static_cast<std::size_t>(nv) * 3, text.size() / 2));
  for (long long i = 0; i < nv; ++i)
    for (int k = 0; k < 3; ++k) s.xyz.push_back(tk.real("a vertex coordinate"));
  s.tri.reserve(std::min(static_cast<std::size_t>(nf) * 3, text.size() / 2));
  for (long long f = 0; f < nf; ++f) {
    const long long n = tk.integer("a face size");
    if (n != 3) tk.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " vertices; only triangles are supported");
    for (int k = 0; k < 3; ++k) {
      const long long v = tk.integer("a vertex index");
      if (v < 0 || v >= nv)
        tk.fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + ", out of range [0, " +
                std::to_string(nv) + ")");
      s.tri.push_back(static_cast<Index>(v));
    }
    tk.skip_rest_of_line();  // optional colour
  }
  return s;
}

SurfaceMesh read_off(const std::string& path) { return parse_off(slurp(path), path); }

void write_off(const std::string& path, const SurfaceMesh& s) {
  std::ofstream out(path);
  if (!out) throw InputError(ErrorCode::kBadArgument, "write", -1, path + ": cannot write the file");
  out << "OFF\n" << s.num_points() << ' ' << s.num_triangles() << " 0\n";
  for (Index i = 0; i < s.num_points(); ++i)
    out << fmt(s.xyz[3 * i]) << ' ' << fmt(s.xyz[3 * i + 1]) << ' ' << fmt(s.xyz[3 * i + 2]) << '\n';
  for (Index t = 0; t < s.num_triangles(); ++t)
    out << "3 " << s.tri[3 * t] << ' ' << s.tri[3 * t + 1] << ' ' << s.tri[3 * t + 2] << '\n';
}

TetMesh parse_tetgen(const std::string& node_text, const std::string& ele_text, const std::string& node_name,
                     const std::string& ele_name) {
  Tokens tn(node_text, node_name);
  const long long np = tn.integer("the point count");
  if (tn.integer("the dimension") != 3) tn.fail("only 3D .node files are supported");
  const long long nattr = tn.integer("the attribute count"), nmark = tn.integer("the marker count");
  if (np < 0 || np > INT32_MAX) tn.fail("invalid point count " + std::to_string(np));
  if (nattr < 0 || nattr > INT32_MAX || nmark < 0 || nmark > 1) tn.fail("invalid attribute or marker count");
  TetMesh m;
  long long base = 0;
  for (long long i = 0; i < np; ++i) {
    const long long id = tn.integer("a point index");
    if (i == 0) base = id;
    if (i == 0 && id != 0 && id != 1) tn.fail("the first point index must be 0 or 1, found " + std::to_string(id));
    if (id != base + i) tn.fail("point indices must be consecutive, found " + std::to_string(id));
    for (int k = 0; k < 3; ++k) m.xyz.push_back(tn.real("a coordinate"));
    for (long long a = 0; a < nattr + nmark; ++a) tn.need("an attribute");
  }
  Tokens te(ele_text, ele_name);
  const long long nk = te.integer("the tet count"), npt = te.integer("the nodes per tet");
  if (nk < 0 || nk > INT32_MAX) te.fail("invalid tet count " + std::to_string(nk));
  if (npt != 4 && npt != 10) te.fail("tets must have 4 or 10 nodes");
  const long long eattr = te.integer("the attribute count");
  if (eattr < 0 || eattr > INT32_MAX) te.fail("invalid attribute count " + std::to_string(eattr));
  m.nodes_per_tet = static_cast<int>(npt);
  // TetGen -o2 orders mid-nodes (m34 m14 m12 m23 m24 m13); ours: m12 m23 m31 m14 m24 m34.
  const int from_tetgen[6] = {2, 3, 5, 1, 4, 0};
  for (long long t = 0; t < nk; ++t) {
    te.integer("a tet index");
    Index v[10];
    for (long long k = 0; k < npt; ++k) {
      const long long raw = te.integer("a point index");
      if (raw < base || raw - base >= np)
        te.fail("tet " + std::to_string(t) + " refers to point " + std::to_string(raw) + ", out of range");
      v[k] = static_cast<Index>(raw - base);
    }
    for (int k = 0; k < 4; ++k) m.tet.push_back(v[k]);
    if (npt == 10)
      for (int k = 0; k < 6; ++k) m.tet.push_back(v[4 + from_tetgen[k]]);
    for (long long a = 0; a < eattr; ++a) te.need("an attribute");
  }
  return m;
}

TetMesh read_tetgen(const std::string& stem) {
  const std::string node_path = stem + ".node", ele_path = stem + ".ele";
  return parse_tetgen(slurp(node_path), slurp(ele_path), node_path, ele_path);
}

void write_tetgen(const std::string& stem, const TetMesh& m) {
  std::ofstream node(stem + ".node"), ele(stem + ".ele");
  if (!node || !ele) throw InputError(ErrorCode::kBadArgument, "write", -1, stem + ": cannot write .node/.ele");
  node << m.num_points() << " 3 0 0\n";
  for (Index i = 0; i < m.num_points(); ++i)
    node << i + 1 << ' ' << fmt(m.xyz[3 * i]) << ' ' << fmt(m.xyz[3 * i + 1]) << ' ' << fmt(m.xyz[3 * i + 2]) << '\n';
  ele << m.num_tets() << ' ' << m.nodes_per_tet << " 0\n";
  const int to_tetgen[6] = {5, 3, 0, 1, 4, 2};  // TetGen slot k takes our mid-node to_tetgen[k]
  for (Index t = 0; t < m.num_tets(); ++t) {
    const Index* v = &m.tet[static_cast<std::size_t>(t) * m.nodes_per_tet];
    ele << t + 1;
    for (int k = 0; k < 4; ++k) ele << ' ' << v[k] + 1;
    if (m.nodes_per_tet == 10)
      for (int k = 0; k < 6; ++k) ele << ' ' << v[4 + to_tetgen[k]] + 1;
    ele << '\n';
  }
}

}  // namespace bsptet
