// The vocabulary tree: construction from node records, descent, BoW transform and scoring.
#include "components/core/place/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace heslam {
namespace {

// Node depth is kept in a byte (ORBvoc.txt has 6 levels).
constexpr int kMaxLevels = 255;

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

Vocabulary::Vocabulary(int branching, int levels, BowScoring scoring, BowWeighting weighting,
                       std::span<const NodeRecord> nodes)
    : branching_(branching), levels_(levels), scoring_(scoring), weighting_(weighting) {
  if (branching < 1) throw std::invalid_argument("vocabulary: branching factor k must be >= 1, got " + std::to_string(branching));
  if (levels < 1 || levels > kMaxLevels) {
    throw std::invalid_argument("vocabulary: levels L must be in 1.." + std::to_string(kMaxLevels) + ", got " + std::to_string(levels));
  }
  const std::size_t n = nodes.size() + 1;
  parent_.resize(n, 0);
  descriptor_.resize(n, Descriptor{});
  weight_.resize(n, 0.f);
  word_.resize(n, kNoWord);
  depth_.resize(n, 0);
  std::vector<std::uint32_t> child_count(n, 0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const NodeId id = static_cast<NodeId>(i + 1);
    const NodeRecord& record = nodes[i];
    if (record.parent >= id) {
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " has parent " + std::to_string(record.parent) +
                                  ", which is not an earlier node");
    }
    if (word_[record.parent] != kNoWord) {
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " has parent " + std::to_string(record.parent) +
                                  ", which is a leaf");
    }
    const int depth = depth_[record.parent] + 1;
    if (depth > kMaxLevels) throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " is deeper than " + std::to_string(kMaxLevels) + " levels");
    if (!std::isfinite(record.weight)) {
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " has a non-finite weight");
    }
    parent_[id] = record.parent;
    descriptor_[id] = record.descriptor;
    weight_[id] = record.weight;
    depth_[id] = static_cast<std::uint8_t>(depth);
    ++child_count[record.parent];
    if (record.is_leaf) {
      word_[id] = static_cast<WordId>(node_of_word_.size());
      node_of_word_.push_back(id);
    }
  }
  // CSR children, in node-id order within each parent (DBoW2's order: first child wins ties).
  child_begin_.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) child_begin_[i + 1] = child_begin_[i] + child_count[i];
  child_.resize(child_begin_[n]);
  std::vector<std::uint32_t> fill(child_begin_.begin(), child_begin_.end() - 1);
  for (std::size_t id = 1; id < n; ++id) child_[fill[parent_[id]]++] = static_cast<NodeId>(id);
  // An inner node without children would swallow descriptors without a word.
  for (std::size_t id = 0; id < n; ++id) {
    if (word_[id] == kNoWord && child_count[id] == 0 && n > 1) {
      throw std::invalid_argument("vocabulary: node " + std::to_string(id) + " is neither a leaf nor has children");
    }
  }
}

WordId Vocabulary::word_of(const Descriptor& descriptor) const {
  if (empty()) return kNoWord;
  NodeId node = 0;
  while (word_[node] == kNoWord) {
    const std::uint32_t begin = child_begin_[node];
    const std::uint32_t end = child_begin_[node + 1];
    NodeId best = child_[begin];
    int best_distance = hamming_distance(descriptor, descriptor_[best]);
    for (std::uint32_t c = begin + 1; c < end; ++c) {
      const int distance = hamming_distance(descriptor, descriptor_[child_[c]]);
      if (distance < best_distance) {
        best_distance = distance;
        best = child_[c];
      }
    }
    node = best;
  }
  return word_[node];
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
  for (std::uint32_t i = 0; i < descriptors.size(); ++i) {
    NodeId node = 0;
    NodeId feature_node = 0;
    while (word_[node] == kNoWord) {
      const std::uint32_t begin = child_begin_[node];
      const std::uint32_t end = child_begin_[node + 1];
      NodeId best = child_[begin];
      int best_distance = hamming_distance(descriptors[i], descriptor_[best]);
      for (std::uint32_t c = begin + 1; c < end; ++c) {
        const int distance = hamming_distance(descriptors[i], descriptor_[child_[c]]);
        if (distance < best_distance) {
          best_distance = distance;
          best = child_[c];
        }
      }
      node = best;
      if (depth_[node] <= feature_depth) feature_node = node;
    }
    words.emplace_back(word_[node], i);
    if (features) filed.emplace_back(feature_node, i);
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
      case BowWeighting::kTfIdf: value = count * idf; break;   // normalised below: tf = count / n
      case BowWeighting::kTf: value = count; break;
      case BowWeighting::kIdf: value = idf; break;            // DBoW2 adds idf once per word
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
        case BowScoring::kChiSquare: if (va + vb != 0.0) sum += va * vb / (va + vb); break;
        case BowScoring::kKl: if (va > 0.0 && vb > 0.0) sum += va * std::log(va / vb); break;
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
    records.push_back({parent_[id], word_[id] != kNoWord, descriptor_[id], weight_[id]});
  }
  return records;
}

}  // namespace heslam
