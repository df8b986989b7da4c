// Supernodal block Cholesky: symbolic analysis on the block graph (elimination tree, column patterns,
// relaxed supernodes), then a left-looking numeric factorization of dense panels with Eigen's products.
#include "components/core/solve/block_sparse_cholesky.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

namespace heslam {
namespace {

// Relaxed supernodes: consecutive columns of an elimination-tree chain share a panel while at most
// this share of its stored blocks are explicit zeros, up to this many block columns. Dense products
// of wider panels run several times faster than the few extra zeros cost (CHOLMOD relaxes the same
// way, 5-80 % zeros by width).
constexpr double kMaxZeroShare = 0.2;
constexpr int kMaxSupernodeBlocks = 16;

using Panel = Eigen::Map<Eigen::MatrixXd>;
using ConstPanel = Eigen::Map<const Eigen::MatrixXd>;

}  // namespace

void BlockSparseCholesky::analyze(const Eigen::SparseMatrix<double>& H_lower, int block_size) {
  if (block_size <= 0 || H_lower.rows() != H_lower.cols() || H_lower.rows() % block_size != 0) {
    throw std::invalid_argument("BlockSparseCholesky: expected a square matrix of " + std::to_string(block_size) +
                                " x " + std::to_string(block_size) + " blocks, got " + std::to_string(H_lower.rows()) +
                                " x " + std::to_string(H_lower.cols()));
  }
  const int D = block_size;
  const int n = static_cast<int>(H_lower.cols()) / D;
  block_size_ = D;
  blocks_ = n;

  // H's block rows below the diagonal, per block column.
  std::vector<std::vector<int>> below(n);
  for (int j = 0; j < n; ++j) {
    for (int c = D * j; c < D * (j + 1); ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(H_lower, c); it; ++it) {
        const int i = static_cast<int>(it.row()) / D;
        if (i > j) below[j].push_back(i);
      }
    }
    std::sort(below[j].begin(), below[j].end());
    below[j].erase(std::unique(below[j].begin(), below[j].end()), below[j].end());
  }

  // Elimination tree (Liu's algorithm with path compression), from each row's entries left of the diagonal.
  std::vector<std::vector<int>> left(n);
  for (int j = 0; j < n; ++j) {
    for (const int i : below[j]) left[i].push_back(j);
  }
  std::vector<int> parent(n, -1), ancestor(n, -1);
  for (int k = 0; k < n; ++k) {
    for (const int j : left[k]) {
      for (int i = j; i != -1 && i < k;) {
        const int next = ancestor[i];
        ancestor[i] = k;
        if (next == -1) parent[i] = k;
        i = next;
      }
    }
  }
  left.clear();

  // L's pattern below the diagonal: H's, plus each child's minus the column itself.
  std::vector<std::vector<int>> children(n);
  for (int j = 0; j < n; ++j) {
    if (parent[j] >= 0) children[parent[j]].push_back(j);
  }
  std::vector<std::vector<int>> pattern(n);
  std::vector<int> marker(n, -1);
  for (int j = 0; j < n; ++j) {
    std::vector<int>& rows = pattern[j];
    rows = below[j];
    for (const int i : rows) marker[i] = j;
    for (const int child : children[j]) {
      for (const int i : pattern[child]) {
        if (i != j && marker[i] != j) {
          marker[i] = j;
          rows.push_back(i);
        }
      }
    }
    std::sort(rows.begin(), rows.end());
  }

  // Supernodes: chains j -> j + 1 of the tree, while the explicit zeros stay few.
  first_block_.clear();
  rows_.clear();
  supernode_of_.assign(n, -1);
  for (int f = 0; f < n;) {
    int l = f;
    std::size_t true_blocks = 1 + pattern[f].size();
    while (l + 1 < n && parent[l] == l + 1) {
      const std::size_t width = l + 2 - f;
      const std::size_t stored = width * (width + 1) / 2 + width * pattern[l + 1].size();
      const std::size_t truth = true_blocks + 1 + pattern[l + 1].size();
      if (static_cast<int>(width) > kMaxSupernodeBlocks ||
          static_cast<double>(stored - truth) > kMaxZeroShare * static_cast<double>(stored)) {
        break;
      }
      true_blocks = truth;
      ++l;
    }
    const int s = static_cast<int>(first_block_.size());
    first_block_.push_back(f);
    std::vector<int> rows;
    for (int j = f; j <= l; ++j) {
      rows.push_back(j);
      supernode_of_[j] = s;
    }
    rows.insert(rows.end(), pattern[l].begin(), pattern[l].end());
    rows_.push_back(std::move(rows));
    f = l + 1;
  }
  first_block_.push_back(n);

  // Which earlier supernodes update each one: the runs of a panel's rows below its own columns that
  // fall in one later supernode's columns.
  const int supernodes = this->supernodes();
  updates_.assign(supernodes, {});
  offset_.assign(supernodes + 1, 0);
  std::size_t workspace = 0;
  for (int d = 0; d < supernodes; ++d) {
    const std::vector<int>& rows = rows_[d];
    const int width = first_block_[d + 1] - first_block_[d];
    const int count = static_cast<int>(rows.size());
    offset_[d + 1] = offset_[d] + static_cast<std::size_t>(D * count) * static_cast<std::size_t>(D * width);
    for (int begin = width; begin < count;) {
      const int target = supernode_of_[rows[begin]];
      int end = begin;
      while (end < count && supernode_of_[rows[end]] == target) ++end;
      updates_[target].push_back({d, begin, end});
      workspace = std::max(workspace,
                           static_cast<std::size_t>(D * (count - begin)) * static_cast<std::size_t>(D * (end - begin)));
      begin = end;
    }
  }
  values_.assign(offset_.back(), 0.0);
  workspace_.assign(workspace, 0.0);
  position_.assign(n, -1);
}

bool BlockSparseCholesky::factorize(const Eigen::SparseMatrix<double>& H_lower) {
  const int D = block_size_;
  if (H_lower.cols() != static_cast<Eigen::Index>(D) * blocks_ || H_lower.rows() != H_lower.cols()) {
    throw std::invalid_argument("BlockSparseCholesky::factorize: the matrix is not the one analysed");
  }
  for (int s = 0; s < supernodes(); ++s) {
    const int first = first_block_[s];
    const int k = D * (first_block_[s + 1] - first);
    const std::vector<int>& rows = rows_[s];
    const int m = D * static_cast<int>(rows.size());
    Panel panel(values_.data() + offset_[s], m, k);
    panel.setZero();
    for (int i = 0; i < static_cast<int>(rows.size()); ++i) position_[rows[i]] = i;

    for (int c = 0; c < k; ++c) {
      const int column = D * first + c;
      for (Eigen::SparseMatrix<double>::InnerIterator it(H_lower, column); it; ++it) {
        const int row = static_cast<int>(it.row());
        if (row >= column) panel(D * position_[row / D] + row % D, c) = it.value();
      }
    }

    // Left-looking: subtract L_source(rows >= begin) L_source(rows [begin, end))^T of every earlier panel.
    for (const Update& update : updates_[s]) {
      const std::vector<int>& source_rows = rows_[update.source];
      const int source_count = static_cast<int>(source_rows.size());
      const ConstPanel source(values_.data() + offset_[update.source], D * source_count,
                              D * (first_block_[update.source + 1] - first_block_[update.source]));
      const int a = D * (source_count - update.begin), b = D * (update.end - update.begin);
      Panel product(workspace_.data(), a, b);
      product.noalias() = source.bottomRows(a) * source.middleRows(D * update.begin, b).transpose();
      for (int cb = update.begin; cb < update.end; ++cb) {
        const int column = D * (source_rows[cb] - first);
        // Runs of rows that are consecutive in this panel too, one block operation each.
        for (int rb = cb; rb < source_count;) {
          const int start = rb;
          while (rb + 1 < source_count && position_[source_rows[rb + 1]] == position_[source_rows[rb]] + 1) ++rb;
          ++rb;
          panel.block(D * position_[source_rows[start]], column, D * (rb - start), D) -=
              product.block(D * (start - update.begin), D * (cb - update.begin), D * (rb - start), D);
        }
      }
    }

    Eigen::Ref<Eigen::MatrixXd> diagonal(panel.topRows(k));
    const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(diagonal);
    if (llt.info() != Eigen::Success) return false;
    if (m > k) {
      auto lower = panel.bottomRows(m - k);
      diagonal.triangularView<Eigen::Lower>().transpose().solveInPlace<Eigen::OnTheRight>(lower);
    }
  }
  return true;
}

Eigen::VectorXd BlockSparseCholesky::solve(const Eigen::VectorXd& b) const {
  const int D = block_size_;
  Eigen::VectorXd x = b;
  Eigen::VectorXd below;
  for (int s = 0; s < supernodes(); ++s) {
    const int first = first_block_[s], width = first_block_[s + 1] - first;
    const std::vector<int>& rows = rows_[s];
    const int m = D * static_cast<int>(rows.size()), k = D * width;
    const ConstPanel panel(values_.data() + offset_[s], m, k);
    auto xs = x.segment(D * first, k);
    panel.topRows(k).triangularView<Eigen::Lower>().solveInPlace(xs);
    if (m == k) continue;
    below.noalias() = panel.bottomRows(m - k) * xs;
    for (int i = width; i < static_cast<int>(rows.size()); ++i)
      x.segment(D * rows[i], D) -= below.segment(D * (i - width), D);
  }
  for (int s = supernodes() - 1; s >= 0; --s) {
    const int first = first_block_[s], width = first_block_[s + 1] - first;
    const std::vector<int>& rows = rows_[s];
    const int m = D * static_cast<int>(rows.size()), k = D * width;
    const ConstPanel panel(values_.data() + offset_[s], m, k);
    auto xs = x.segment(D * first, k);
    if (m > k) {
      below.resize(m - k);
      for (int i = width; i < static_cast<int>(rows.size()); ++i)
        below.segment(D * (i - width), D) = x.segment(D * rows[i], D);
      xs.noalias() -= panel.bottomRows(m - k).transpose() * below;
    }
    panel.topRows(k).triangularView<Eigen::Lower>().transpose().solveInPlace(xs);
  }
  return x;
}

std::size_t BlockSparseCholesky::stored_entries() const {
  std::size_t entries = 0;
  for (int s = 0; s < supernodes(); ++s) {
    const std::size_t k = static_cast<std::size_t>(block_size_) * (first_block_[s + 1] - first_block_[s]);
    const std::size_t m = static_cast<std::size_t>(block_size_) * rows_[s].size();
    entries += m * k - k * (k - 1) / 2;
  }
  return entries;
}

}  // namespace heslam
