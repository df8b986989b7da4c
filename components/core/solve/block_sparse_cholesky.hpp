// Supernodal Cholesky factorization H = L L^T of a sparse symmetric positive definite matrix made of
// dense square blocks (the normal equations of a pose graph: a 6x6 block per keyframe and one per
// edge), in the order given (the caller orders the blocks to reduce fill, e.g. AMD on its graph).
// Columns of L with the same pattern below them (relaxed: up to a fifth explicit zeros) form a
// supernode stored as one dense panel, so the factorization runs as dense products of panels
// (left-looking, as CHOLMOD's supernodal method) instead of scalar sparse updates: where the pattern
// has fill (a loop closing a long chain of keyframes doubles L), that is what keeps it fast.
// Single-threaded and deterministic: the same matrix gives the same factor bit for bit.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace heslam {

class BlockSparseCholesky {
 public:
  // The pattern of H's lower triangle (entries with row >= column, column-major), made of dense
  // block_size x block_size blocks: block (i, j) is present when H's column block_size * j holds a
  // row of block i. Call again when the pattern changes.
  void analyze(const Eigen::SparseMatrix<double>& H_lower, int block_size);

  // Factorizes H (the pattern analyze saw; only its lower triangle is read). False when H is not
  // positive definite (the factor is then unusable).
  bool factorize(const Eigen::SparseMatrix<double>& H_lower);

  // x with H x = b, after a successful factorize.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;

  int supernodes() const { return static_cast<int>(first_block_.size()) - 1; }
  // Entries of L stored (the lower trapezoid of every panel, explicit zeros included).
  std::size_t stored_entries() const;

 private:
  struct Update {  // what supernode `source` contributes to a later supernode
    int source = 0;
    int begin = 0;  // the source's rows [begin, end) fall in the target's columns; rows >= end below them
    int end = 0;
  };

  int block_size_ = 0;
  int blocks_ = 0;
  std::vector<int> first_block_;              // per supernode: its first block column; one past the end last
  std::vector<std::vector<int>> rows_;        // per supernode: its block rows, its own columns first
  std::vector<std::size_t> offset_;           // per supernode: its panel's first value in values_
  std::vector<std::vector<Update>> updates_;  // per supernode: the earlier supernodes that update it
  std::vector<int> supernode_of_;             // per block column
  std::vector<double> values_;                // the panels, column-major, rows x columns each
  std::vector<double> workspace_;             // a product of two panels' parts
  std::vector<int> position_;                 // per block row: its row in the supernode being factorized
};

}  // namespace heslam
