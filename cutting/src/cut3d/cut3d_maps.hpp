#pragma once
// Keys, small hash maps and the tet's local numbering shared by the stages of a 3D cut.
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "hysim/cutting/tet_faces.hpp"

namespace hysim::cutting::cut3d_detail {

using Vec3 = Eigen::Vector3d;
using Tet = std::array<std::int32_t, 4>;

inline std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

struct FaceKey {
  std::array<std::int32_t, 3> v;
  bool operator==(const FaceKey& o) const { return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2]; }
  bool operator<(const FaceKey& o) const {
    return v[0] != o.v[0] ? v[0] < o.v[0] : v[1] != o.v[1] ? v[1] < o.v[1] : v[2] < o.v[2];
  }
};
struct FaceKeyHash {
  size_t operator()(const FaceKey& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (int x : k.v) h = (h ^ static_cast<std::uint32_t>(x)) * 1099511628211ull;
    return static_cast<size_t>(h);
  }
};
// Open-addressing hash map (linear probing, power-of-two capacity) for the small maps of a
// cut: crossed edges, faces on the cut. Much cheaper than std::unordered_map (no node per
// entry); lookups only, so its layout never affects the results. `empty` is a key no entry
// uses.
template <class Key, class Value, class Hash>
class FlatMap {
 public:
  explicit FlatMap(Key empty) : empty_(empty) { rehash(64); }
  size_t size() const { return size_; }
  // Room for n entries without growing (capacity: a power of two >= 2 n).
  void reserve(size_t n) {
    size_t capacity = keys_.size();
    while (capacity < 2 * n) capacity *= 2;
    if (capacity > keys_.size()) rehash(capacity);
  }
  Value* find(const Key& k) {
    for (size_t i = Hash{}(k) & mask_;; i = (i + 1) & mask_) {
      if (keys_[i] == k) return &vals_[i];
      if (keys_[i] == empty_) return nullptr;
    }
  }
  bool contains(const Key& k) { return find(k) != nullptr; }
  // The value for k, inserting `v` if absent; second: whether it was inserted.
  std::pair<Value*, bool> tryEmplace(const Key& k, const Value& v) {
    if (2 * (size_ + 1) > keys_.size()) rehash(2 * keys_.size());
    size_t i = Hash{}(k) & mask_;
    for (; !(keys_[i] == empty_); i = (i + 1) & mask_)
      if (keys_[i] == k) return {&vals_[i], false};
    keys_[i] = k;
    vals_[i] = v;
    ++size_;
    return {&vals_[i], true};
  }
  template <class F>
  void forEach(F&& f) {
    for (size_t i = 0; i < keys_.size(); ++i)
      if (!(keys_[i] == empty_)) f(keys_[i], vals_[i]);
  }

 private:
  void rehash(size_t capacity) {
    std::vector<Key> keys(capacity, empty_);
    std::vector<Value> vals(capacity);
    keys.swap(keys_);
    vals.swap(vals_);
    mask_ = capacity - 1;
    size_ = 0;
    for (size_t i = 0; i < keys.size(); ++i)
      if (!(keys[i] == empty_)) tryEmplace(keys[i], vals[i]);
  }
  Key empty_;
  std::vector<Key> keys_;
  std::vector<Value> vals_;
  size_t mask_ = 0, size_ = 0;
};
struct EdgeKeyHash {
  size_t operator()(std::uint64_t k) const { return static_cast<size_t>((k * 0x9E3779B97F4A7C15ull) >> 20); }
};
using EdgeMap = FlatMap<std::uint64_t, std::int32_t, EdgeKeyHash>;
inline constexpr std::uint64_t kNoEdge = ~0ull;
struct FaceFlatHash {
  size_t operator()(const FaceKey& k) const {
    const std::uint64_t h = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.v[0])) * 0x9E3779B97F4A7C15ull) ^
                            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.v[1])) * 0xC2B2AE3D27D4EB4Full) ^
                            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.v[2])) * 0x165667B19E3779F9ull);
    return static_cast<size_t>((h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull >> 20);
  }
};
inline constexpr FaceKey kNoFace{{-1, -1, -1}};

inline FaceKey makeFace(std::int32_t a, std::int32_t b, std::int32_t c) {
  // Sorted (three compare-exchanges).
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return FaceKey{{a, b, c}};
}

// Outward faces of a positive tet, by the local index of the opposite vertex.
inline constexpr const auto& kFace = kTetFace;
inline constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
// The three faces of a tet containing its vertex k, each by its two other vertices.
inline constexpr int kFacePairs[4][3][2] = {{{2, 3}, {1, 3}, {1, 2}},
                                            {{2, 3}, {0, 3}, {0, 2}},
                                            {{1, 3}, {0, 3}, {0, 1}},
                                            {{1, 2}, {0, 2}, {0, 1}}};

inline double signedVolume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

inline int findLocal(const Tet& t, int v) {
  for (int k = 0; k < 4; ++k)
    if (t[k] == v) return k;
  return -1;
}

}  // namespace hysim::cutting::cut3d_detail
