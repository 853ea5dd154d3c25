// A run's state in one file, to resume it where it stopped: `flume run --checkpoint-every S` writes it, `flume run
// --resume` continues from it. Every class with state lists its members once, in a `checkpoint(StateArchive&)`
// that both writes and reads (the archive knows which), so saving and loading cannot drift apart. The file is
// a magic, a format version, the scene's identity (its JSON with the overrides, less solver.end_time, so a
// finished run can be extended), the payload and an FNV-1a checksum of it; it is written beside the target and
// renamed over it, so a run killed while writing keeps the previous checkpoint.
#pragma once
#include <array>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/errors.h"

namespace flume {

namespace detail {
template <class T, class = void>
struct is_fixed_matrix : std::false_type {};
template <class T>
struct is_fixed_matrix<T, std::void_t<decltype(T::RowsAtCompileTime), decltype(T::ColsAtCompileTime),
                                      typename T::Scalar, decltype(std::declval<T&>().data())>>
    : std::bool_constant<(T::RowsAtCompileTime > 0 && T::ColsAtCompileTime > 0)> {};
template <class T, class = void>
struct is_quaternion : std::false_type {};
template <class T>
struct is_quaternion<T, std::void_t<typename T::Coefficients, decltype(std::declval<T&>().coeffs())>>
    : std::true_type {};
}  // namespace detail

class StateArchive {
 public:
  // An archive to write into.
  StateArchive() = default;
  // An archive reading `payload`, which came from `file` (named in errors).
  StateArchive(std::string payload, std::string file) : bytes_(std::move(payload)), file_(std::move(file)), loading_(true) {}

  bool loading() const { return loading_; }
  const std::string& bytes() const { return bytes_; }
  const std::string& file() const { return file_; }
  size_t position() const { return pos_; }  // bytes read so far

  // A named mark: written when saving, checked when loading, so that a state read out of step (a different
  // build or scene) is refused where it goes wrong rather than silently misread.
  void section(const std::string& name) {
    std::string s = name;
    (*this)(s);
    if (loading_ && s != name) fail(name, "expected the section '" + name + "', found '" + s + "'");
  }
  // A count that the scene fixes (bodies, gauges): written when saving, checked when loading.
  void expect(const std::string& what, uint64_t n) {
    uint64_t m = n;
    (*this)(m);
    if (loading_ && m != n)
      fail(what, "the checkpoint holds " + std::to_string(m) + ", the scene " + std::to_string(n));
  }

  // A value: a fixed-size Eigen matrix or quaternion by its coefficients, a plain type by its bytes, any other
  // class as `checkpoint_state(StateArchive&, T&)` lists it (found by argument lookup).
  template <class T>
  void operator()(T& v) {
    if constexpr (detail::is_fixed_matrix<T>::value) {
      raw(v.data(), sizeof(typename T::Scalar) * T::RowsAtCompileTime * T::ColsAtCompileTime);
    } else if constexpr (detail::is_quaternion<T>::value) {
      raw(v.coeffs().data(), sizeof(typename T::Scalar) * 4);
    } else if constexpr (std::is_trivially_copyable_v<T>) {
      raw(&v, sizeof(T));
    } else {
      checkpoint_state(*this, v);
    }
  }
  // Several values in order, as one call each.
  template <class... T>
  void fields(T&... v) {
    ((*this)(v), ...);
  }
  void operator()(std::string& s) {
    uint64_t n = s.size();
    (*this)(n);
    if (loading_) {
      need(n);
      s.assign(bytes_.data() + pos_, n);
      pos_ += n;
    } else {
      bytes_.append(s);
    }
  }
  template <class T, class A>
  void operator()(std::vector<T, A>& v) {
    uint64_t n = v.size();
    (*this)(n);
    if constexpr (std::is_trivially_copyable_v<T>) {
      if (loading_) {
        need(n * sizeof(T));
        v.resize(n);
      }
      if (n) raw(v.data(), n * sizeof(T));
    } else {
      if (loading_) v.resize(n);
      for (auto& x : v) (*this)(x);
    }
  }
  template <class K, class V>
  void operator()(std::map<K, V>& m) {
    uint64_t n = m.size();
    (*this)(n);
    if (loading_) {
      m.clear();
      for (uint64_t i = 0; i < n; ++i) {
        K k{};
        (*this)(k);
        (*this)(m[k]);
      }
    } else {
      for (auto& [k, v] : m) {
        K key = k;
        (*this)(key);
        (*this)(v);
      }
    }
  }

  // The end of a load: every byte read.
  void finish() const {
    if (loading_ && pos_ != bytes_.size()) fail("payload", std::to_string(bytes_.size() - pos_) + " bytes left over");
  }

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw InputError(file_, field, "checkpoint does not fit this run: " + what);
  }

 private:
  void need(uint64_t n) const {
    if (n > bytes_.size() - pos_) fail("payload", "truncated");
  }
  void raw(void* p, size_t n) {
    if (loading_) {
      need(n);
      std::memcpy(p, bytes_.data() + pos_, n);
      pos_ += n;
    } else {
      bytes_.append(static_cast<const char*>(p), n);
    }
  }

  std::string bytes_;
  std::string file_;
  bool loading_ = false;
  size_t pos_ = 0;
};

// The scene's identity for a checkpoint: its JSON (overrides applied) without solver.end_time, canonical.
std::string checkpoint_scene_key(const std::string& source_json);

// Writes `payload` to `path` (through path + ".part" and a rename). Throws InputError naming the file.
void write_checkpoint_file(const std::string& path, const std::string& scene_key, const std::string& payload);
// Reads a checkpoint written by write_checkpoint_file; refuses (InputError naming the file) a missing,
// truncated or corrupt file, another format version, or another scene.
std::string read_checkpoint_file(const std::string& path, const std::string& scene_key);

}  // namespace flume
