// The vocabulary tree: construction from node records, descent, BoW transform and scoring.
#include "components/core/place/vocabulary.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace heslam {
namespace {

// Node depth is kept in a byte (ORBvoc.txt has 6 levels).
constexpr int kMaxLevels = 255;
constexpr std::size_t kDescriptorBytes = sizeof(Descriptor);
// Descriptors descending together in transform(): enough independent cache misses in flight to
// keep the memory system busy on a 1M-word tree, few enough that their state stays in registers/L1.
constexpr std::size_t kDescentBatch = 16;
constexpr std::size_t kCacheLineBytes = 64;

void prefetch(const void* data, std::size_t bytes) {
  const char* p = static_cast<const char*>(data);
  for (std::size_t offset = 0; offset < bytes; offset += kCacheLineBytes) __builtin_prefetch(p + offset);
}

// DBoW2 normalises with the L1 norm for L1 scoring (ORBvoc.txt); every scoring gets it here.
void l1_normalise(BowVector& bow) {
  double sum = 0.0;
  for (const auto& [word, weight] : bow.entries) sum += std::abs(weight);
  if (sum <= 0.0) return;
  const float inv = static_cast<float>(1.0 / sum);
  for (auto& entry : bow.entries) entry.second *= inv;
}

}  // namespace

const char* to_string(BowWeighting weighting) {
  switch (weighting) {
    case BowWeighting::kTfIdf: return "tf-idf";
    case BowWeighting::kTf: return "tf";
    case BowWeighting::kIdf: return "idf";
    case BowWeighting::kBinary: return "binary";
  }
  return "unknown";
}

const char* to_string(BowScoring scoring) {
  switch (scoring) {
    case BowScoring::kL1: return "L1";
    case BowScoring::kL2: return "L2";
    case BowScoring::kChiSquare: return "chi-square";
    case BowScoring::kKl: return "KL";
    case BowScoring::kBhattacharyya: return "Bhattacharyya";
    case BowScoring::kDotProduct: return "dot-product";
  }
  return "unknown";
}

Vocabulary::Vocabulary(int branching, int levels, BowScoring scoring, BowWeighting weighting)
    : branching_(branching), levels_(levels), scoring_(scoring), weighting_(weighting) {
  if (branching < 1)
    throw std::invalid_argument("vocabulary: branching factor k must be >= 1, got " + std::to_string(branching));
  if (levels < 1 || levels > kMaxLevels) {
    throw std::invalid_argument("vocabulary: levels L must be in 1.." + std::to_string(kMaxLevels) + ", got " +
                                std::to_string(levels));
  }
}

Vocabulary::Vocabulary(int branching, int levels, BowScoring scoring, BowWeighting weighting,
                       std::span<const NodeRecord> nodes)
    : Vocabulary(branching, levels, scoring, weighting) {
  const std::size_t n = nodes.size() + 1;
  parent_.resize(n, 0);
  weight_.resize(n, 0.f);
  std::vector<std::uint8_t> is_leaf(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    parent_[i + 1] = nodes[i].parent;
    weight_[i + 1] = nodes[i].weight;
    is_leaf[i] = nodes[i].is_leaf ? 1 : 0;
  }
  link(is_leaf, [&](std::size_t id) -> const Descriptor& { return nodes[id - 1].descriptor; });
}

Vocabulary Vocabulary::from_columns(int branching, int levels, BowScoring scoring, BowWeighting weighting,
                                    const NodeColumns& columns) {
  const std::size_t n = columns.is_leaf.size();
  if (columns.parents.size() != 4 * n || columns.descriptors.size() != kDescriptorBytes * n ||
      columns.weights.size() != 4 * n) {
    throw std::invalid_argument("vocabulary: node columns of different lengths");
  }
  Vocabulary vocabulary(branching, levels, scoring, weighting);
  vocabulary.parent_.resize(n + 1, 0);
  vocabulary.weight_.resize(n + 1, 0.f);
  std::memcpy(vocabulary.parent_.data() + 1, columns.parents.data(), columns.parents.size());
  std::memcpy(vocabulary.weight_.data() + 1, columns.weights.data(), columns.weights.size());
  vocabulary.link(columns.is_leaf, [&](std::size_t id) {
    Descriptor descriptor;
    std::memcpy(descriptor.data(), columns.descriptors.data() + kDescriptorBytes * (id - 1), kDescriptorBytes);
    return descriptor;
  });
  return vocabulary;
}

template <typename DescriptorOf>
void Vocabulary::link(std::span<const std::uint8_t> is_leaf, DescriptorOf&& descriptor_of) {
  const std::size_t n = parent_.size();
  word_.assign(n, kNoWord);
  std::vector<std::uint8_t> depth(n, 0);
  std::vector<std::uint32_t> child_count(n, 0);
  for (std::size_t id = 1; id < n; ++id) {
    const NodeId parent = parent_[id];
    if (parent >= id) {
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " has parent " + std::to_string(parent) +
                                  ", which is not an earlier node");
    }
    if (word_[parent] != kNoWord) {
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " has parent " + std::to_string(parent) +
                                  ", which is a leaf");
    }
    if (depth[parent] + 1 > kMaxLevels)
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " is deeper than " +
                                  std::to_string(kMaxLevels) + " levels");
    if (!std::isfinite(weight_[id]))
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " has a non-finite weight");
    depth[id] = static_cast<std::uint8_t>(depth[parent] + 1);
    ++child_count[parent];
    if (is_leaf[id - 1]) {
      word_[id] = static_cast<WordId>(node_of_word_.size());
      node_of_word_.push_back(static_cast<NodeId>(id));
    }
  }
  // Children in node-id order within each parent (DBoW2's order: first child wins ties).
  std::vector<std::uint32_t> first_slot(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) first_slot[i + 1] = first_slot[i] + child_count[i];
  slot_.resize(n - 1);
  slot_descriptor_.resize(n - 1);
  slot_of_node_.assign(n, 0);
  std::vector<std::uint32_t> fill(first_slot.begin(), first_slot.end() - 1);
  for (std::size_t id = 1; id < n; ++id) {
    const std::uint32_t slot = fill[parent_[id]]++;
    slot_of_node_[id] = slot;
    slot_descriptor_[slot] = descriptor_of(id);
    Slot& s = slot_[slot];
    s.node = static_cast<NodeId>(id);
    if (word_[id] != kNoWord) {
      s.first_child_or_word = word_[id];
    } else if (child_count[id] == 0) {
      // An inner node without children would swallow descriptors without a word.
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " is neither a leaf nor has children");
    } else {
      s.first_child_or_word = first_slot[id];
      s.child_count = child_count[id];
    }
  }
  root_ = {0, first_slot[0], child_count[0]};
}

std::uint32_t Vocabulary::closest_child(const Descriptor& descriptor, const Slot& node) const {
  const std::uint32_t begin = node.first_child_or_word;
  const std::uint32_t end = begin + node.child_count;
  std::uint32_t best = begin;
  int best_distance = hamming_distance(descriptor, slot_descriptor_[begin]);
  for (std::uint32_t c = begin + 1; c < end; ++c) {
    const int distance = hamming_distance(descriptor, slot_descriptor_[c]);
    if (distance < best_distance) {
      best_distance = distance;
      best = c;
    }
  }
  return best;
}

WordId Vocabulary::word_of(const Descriptor& descriptor) const {
  if (empty()) return kNoWord;
  const Slot* at = &root_;
  while (true) {
    at = &slot_[closest_child(descriptor, *at)];
    if (at->child_count == 0) return at->first_child_or_word;
  }
}

float Vocabulary::word_weight(WordId word) const { return weight_[node_of_word_[word]]; }

void Vocabulary::transform(std::span<const Descriptor> descriptors, BowVector& bow, FeatureVector* features,
                           int levels_up) const {
  bow.entries.clear();
  if (features) features->nodes.clear();
  if (empty() || descriptors.empty()) return;
  const int feature_depth = std::max(0, levels_ - levels_up);

  // (word, feature) and (node, feature) pairs, sorted once: no per-word allocation.
  std::vector<std::pair<WordId, std::uint32_t>> words;
  words.reserve(descriptors.size());
  std::vector<std::pair<NodeId, std::uint32_t>> filed;
  if (features) filed.reserve(descriptors.size());
  // Descriptors descend kDescentBatch at a time, one level per round: after each step the next
  // step's blocks are prefetched and the other descriptors' steps overlap their cache misses.
  std::array<const Slot*, kDescentBatch> at{};
  std::array<NodeId, kDescentBatch> feature_node{};
  for (std::size_t base = 0; base < descriptors.size(); base += kDescentBatch) {
    const std::size_t batch = std::min(kDescentBatch, descriptors.size() - base);
    at.fill(&root_);
    feature_node.fill(0);
    std::size_t remaining = batch;
    for (int depth = 1; remaining > 0; ++depth) {
      for (std::size_t g = 0; g < batch; ++g) {
        if (at[g] == nullptr) continue;
        const Descriptor& descriptor = descriptors[base + g];
        const Slot& chosen = slot_[closest_child(descriptor, *at[g])];
        if (depth <= feature_depth) feature_node[g] = chosen.node;
        if (chosen.child_count == 0) {
          const auto index = static_cast<std::uint32_t>(base + g);
          words.emplace_back(chosen.first_child_or_word, index);
          if (features) filed.emplace_back(feature_node[g], index);
          at[g] = nullptr;
          --remaining;
          continue;
        }
        at[g] = &chosen;
        prefetch(slot_descriptor_.data() + chosen.first_child_or_word, chosen.child_count * sizeof(Descriptor));
        prefetch(slot_.data() + chosen.first_child_or_word, chosen.child_count * sizeof(Slot));
      }
    }
  }

  std::sort(words.begin(), words.end());
  for (std::size_t i = 0; i < words.size();) {
    const WordId word = words[i].first;
    std::size_t j = i;
    while (j < words.size() && words[j].first == word) ++j;
    const float count = static_cast<float>(j - i);
    const float idf = weight_[node_of_word_[word]];
    float value = 0.f;
    switch (weighting_) {
      case BowWeighting::kTfIdf: value = count * idf; break;  // normalised below: tf = count / n
      case BowWeighting::kTf: value = count; break;
      case BowWeighting::kIdf: value = idf; break;  // DBoW2 adds idf once per word
      case BowWeighting::kBinary: value = 1.f; break;
    }
    if (value > 0.f) bow.entries.emplace_back(word, value);
    i = j;
  }
  l1_normalise(bow);

  if (features) {
    std::sort(filed.begin(), filed.end());
    for (std::size_t i = 0; i < filed.size();) {
      const NodeId node = filed[i].first;
      std::vector<std::uint32_t> indices;
      std::size_t j = i;
      while (j < filed.size() && filed[j].first == node) indices.push_back(filed[j++].second);
      features->nodes.emplace_back(node, std::move(indices));
      i = j;
    }
  }
}

double Vocabulary::score(const BowVector& a, const BowVector& b) const {
  // Merge over the two sorted vectors; only words in both contribute to these forms.
  auto ia = a.entries.begin();
  auto ib = b.entries.begin();
  double sum = 0.0;
  while (ia != a.entries.end() && ib != b.entries.end()) {
    if (ia->first < ib->first) {
      ++ia;
    } else if (ib->first < ia->first) {
      ++ib;
    } else {
      const double va = ia->second;
      const double vb = ib->second;
      switch (scoring_) {
        // |a-b|_1 = |a|_1 + |b|_1 - sum over common words of (|va| + |vb| - |va - vb|) = 2 - that sum.
        case BowScoring::kL1: sum += std::abs(va - vb) - std::abs(va) - std::abs(vb); break;
        case BowScoring::kL2: sum += va * vb; break;
        case BowScoring::kChiSquare:
          if (va + vb != 0.0) sum += va * vb / (va + vb);
          break;
        case BowScoring::kKl:
          if (va > 0.0 && vb > 0.0) sum += va * std::log(va / vb);
          break;
        case BowScoring::kBhattacharyya: sum += std::sqrt(va * vb); break;
        case BowScoring::kDotProduct: sum += va * vb; break;
      }
      ++ia;
      ++ib;
    }
  }
  switch (scoring_) {
    case BowScoring::kL1: return -sum / 2.0;  // DBoW2: 1 - 0.5 |a - b|_1 for L1-normalised vectors
    case BowScoring::kL2: return sum >= 1.0 ? 1.0 : 1.0 - std::sqrt(1.0 - sum);
    case BowScoring::kChiSquare: return 2.0 * sum;
    case BowScoring::kKl: return sum;
    case BowScoring::kBhattacharyya: return sum;
    case BowScoring::kDotProduct: return sum;
  }
  return 0.0;
}

std::vector<Vocabulary::NodeRecord> Vocabulary::node_records() const {
  std::vector<NodeRecord> records;
  records.reserve(parent_.empty() ? 0 : parent_.size() - 1);
  for (std::size_t id = 1; id < parent_.size(); ++id) {
    records.push_back({parent_[id], word_[id] != kNoWord, slot_descriptor_[slot_of_node_[id]], weight_[id]});
  }
  return records;
}

}  // namespace heslam
