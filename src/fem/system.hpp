// The discrete system: degrees of freedom (3 per node, global index 3 node + axis) split into
// free and prescribed ones, a sparsity pattern computed once, and in-place assembly of the
// energy, internal force and tangent blocks K_ff (lower triangle) and K_fp.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "fem/element.hpp"
#include "phymul/fem.hpp"

namespace phymul::fem {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

class System {
 public:
  // `prescribed[3 node + axis]` marks the imposed components. Nodes used by no cell have no
  // stiffness, so their components are treated as prescribed too (at whatever value the
  // caller imposes, zero by default). The mesh must be valid hexa/tetra (checked before).
  System(const Mesh& mesh, const Material& material, std::vector<char> prescribed);
  // Cell c of materials[cell_material[c]] (several objects in one system).
  System(const Mesh& mesh, const std::vector<Material>& materials,
         const std::vector<int>& cell_material, std::vector<char> prescribed);

  int dof_count() const { return int(dof_index_.size()); }
  int free_count() const { return int(free_dofs_.size()); }
  int prescribed_count() const { return int(prescribed_dofs_.size()); }
  const std::vector<int>& free_dofs() const { return free_dofs_; }
  const std::vector<int>& prescribed_dofs() const { return prescribed_dofs_; }

  // Consistent nodal forces (all dofs) of a body force per unit reference volume.
  Eigen::VectorXd body_force(const Vec3& force_density) const;

  // Energy, internal force and, when asked, the tangent at the displacement u (all dofs).
  // Returns false when the deformation inverts an element; the outputs are then invalid.
  bool evaluate(const Eigen::VectorXd& u, bool with_tangent);

  double energy() const { return energy_; }
  const Eigen::VectorXd& internal_force() const { return internal_; }
  const SparseMatrix& free_free() const { return k_ff_; }  // lower triangle only
  const SparseMatrix& free_prescribed() const { return k_fp_; }

  // The last evaluation's outputs (and the incompatible modes it left, the next one's start),
  // and putting them back, so that a resumed solve needs no evaluation of its own.
  void save_evaluation(SolveState& state) const;
  void restore_evaluation(const SolveState& state);
  // K_ff's values, in its fixed pattern.
  std::vector<double> tangent_values() const;
  void set_tangent_values(const std::vector<double>& values);

  Eigen::VectorXd gather(const Eigen::VectorXd& full, const std::vector<int>& dofs) const;
  void scatter_add(const Eigen::VectorXd& part, const std::vector<int>& dofs,
                   Eigen::VectorXd& full) const;

 private:
  struct Element {
    CellType type = CellType::hexa;
    bool incompatible = false;  // a hexahedron with incompatible modes (incompatible_)
    int reference = 0;          // index into hexa_, incompatible_ or tetra_
    int slots = 0;              // offset into slot_ of its (3n)^2 assembly targets
    int law = 0;                // index into laws_
    std::array<int, 8> nodes{};
  };

  void build_pattern();
  template <int NN, int NG>
  bool add_element(const ElementReference<NN, NG>& ref, const Element& element,
                   const Eigen::VectorXd& u, bool with_tangent);
  bool add_incompatible(const Element& element, const Eigen::VectorXd& u, bool with_tangent);
  template <int NN>
  void add_result(const Element& element, const ElementResult<NN>& out, bool with_tangent);

  std::vector<LawConstants> laws_;
  std::vector<HexaReference> hexa_;
  std::vector<TetraReference> tetra_;
  std::vector<IncompatibleHexaReference> incompatible_;
  std::vector<ModeAmplitudes> modes_;  // per incompatible_ element: the last local solution
  std::vector<Element> elements_;
  // Per global dof: free index (>= 0) or -1 - prescribed index.
  std::vector<int> dof_index_;
  std::vector<int> free_dofs_;
  std::vector<int> prescribed_dofs_;
  // Per element entry (r, c), column-major: >= 0 position in k_ff_ values, <= -2 position
  // -2 - slot in k_fp_ values, -1 not assembled (prescribed row or upper triangle).
  std::vector<int> slot_;

  double energy_ = 0.0;
  Eigen::VectorXd internal_;
  SparseMatrix k_ff_;
  SparseMatrix k_fp_;
};

}  // namespace phymul::fem
