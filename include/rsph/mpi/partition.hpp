#pragma once
// The partition of particles among ranks by Zoltan: recursive coordinate bisection (RCB) or the Hilbert
// space-filling curve (HSFC), weighted by each particle's measured work. Zoltan only says where each
// particle should live; moving it is migrate()'s (mpi/decomposition.hpp).
#include "rsph/core/dimension.hpp"
#include "rsph/mpi/comm.hpp"

#include <zoltan.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace rsph::mpi {

/// How Zoltan cuts the domain: "RCB" (boxes, the default) or "HSFC".
struct PartitionParams {
  std::string method = "RCB";
  double imbalance_tol = 1.05;  ///< Zoltan's target for the largest rank's weight over the mean
  void validate() const {
    require(method == "RCB" || method == "HSFC", "the partition method must be RCB or HSFC, not " + method);
    require(imbalance_tol >= 1.0, "the partition's imbalance tolerance must be at least 1");
  }
};

/// A Zoltan load-balancing structure on one communicator (created and destroyed with this object).
template <int D>
class Partitioner {
 public:
  Partitioner(MPI_Comm comm, PartitionParams params) : params_(std::move(params)) {
    params_.validate();
    float version = 0.0f;
    if (Zoltan_Initialize(0, nullptr, &version) != ZOLTAN_OK) throw NumericalError("Zoltan_Initialize failed");
    zz_ = Zoltan_Create(comm);
    if (!zz_) throw NumericalError("Zoltan_Create failed");
    set("DEBUG_LEVEL", "0");
    set("LB_METHOD", params_.method);
    set("NUM_GID_ENTRIES", "2");  // a particle's 64-bit identity
    set("NUM_LID_ENTRIES", "1");
    set("OBJ_WEIGHT_DIM", "1");
    set("RETURN_LISTS", "EXPORT");
    set("IMBALANCE_TOL", std::to_string(params_.imbalance_tol));
    if (params_.method == "RCB") set("RCB_REUSE", "1");  // start from the last cuts: few particles move
    Zoltan_Set_Num_Obj_Fn(zz_, &num_obj, this);
    Zoltan_Set_Obj_List_Fn(zz_, &obj_list, this);
    Zoltan_Set_Num_Geom_Fn(zz_, &num_geom, this);
    Zoltan_Set_Geom_Multi_Fn(zz_, &geom_multi, this);
  }
  Partitioner(const Partitioner&) = delete;
  Partitioner& operator=(const Partitioner&) = delete;
  ~Partitioner() { Zoltan_Destroy(&zz_); }

  /// The rank each of the first n points should live on (this rank for most), from their positions, their
  /// identities and their weights (the work each costs).
  std::vector<int> destinations(std::span<const Vec<D>> x, std::span<const std::uint64_t> id,
                                std::span<const double> weight, int my_rank) {
    x_ = x;
    id_ = id;
    weight_ = weight;
    int changes = 0, n_gid = 0, n_lid = 0, n_import = 0, n_export = 0;
    ZOLTAN_ID_PTR import_gid = nullptr, import_lid = nullptr, export_gid = nullptr, export_lid = nullptr;
    int *import_procs = nullptr, *import_parts = nullptr, *export_procs = nullptr, *export_parts = nullptr;
    const int rc =
        Zoltan_LB_Partition(zz_, &changes, &n_gid, &n_lid, &n_import, &import_gid, &import_lid, &import_procs,
                            &import_parts, &n_export, &export_gid, &export_lid, &export_procs, &export_parts);
    std::vector<int> dest(x.size(), my_rank);
    if (rc == ZOLTAN_OK)
      for (int e = 0; e < n_export; ++e) dest[export_lid[e]] = export_procs[e];
    Zoltan_LB_Free_Part(&import_gid, &import_lid, &import_procs, &import_parts);
    Zoltan_LB_Free_Part(&export_gid, &export_lid, &export_procs, &export_parts);
    if (rc != ZOLTAN_OK) throw NumericalError("Zoltan_LB_Partition failed");
    return dest;
  }

 private:
  void set(const char* name, const std::string& value) {
    if (Zoltan_Set_Param(zz_, name, value.c_str()) != ZOLTAN_OK)
      throw NumericalError(std::string("Zoltan refused its parameter ") + name + " = " + value);
  }
  static Partitioner& self(void* data) { return *static_cast<Partitioner*>(data); }
  static int num_obj(void* data, int* ierr) {
    *ierr = ZOLTAN_OK;
    return static_cast<int>(self(data).x_.size());
  }
  static void obj_list(void* data, int, int, ZOLTAN_ID_PTR gid, ZOLTAN_ID_PTR lid, int, float* w, int* ierr) {
    const auto& s = self(data);
    for (std::size_t a = 0; a < s.x_.size(); ++a) {
      gid[2 * a] = static_cast<ZOLTAN_ID_TYPE>(s.id_[a] >> 32);
      gid[2 * a + 1] = static_cast<ZOLTAN_ID_TYPE>(s.id_[a] & 0xffffffffu);
      lid[a] = static_cast<ZOLTAN_ID_TYPE>(a);
      w[a] = static_cast<float>(s.weight_[a]);
    }
    *ierr = ZOLTAN_OK;
  }
  static int num_geom(void*, int* ierr) {
    *ierr = ZOLTAN_OK;
    return D;
  }
  static void geom_multi(void* data, int, int, int n, ZOLTAN_ID_PTR, ZOLTAN_ID_PTR lid, int, double* xyz, int* ierr) {
    const auto& s = self(data);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < D; ++k) xyz[D * i + k] = s.x_[lid[i]][k];
    *ierr = ZOLTAN_OK;
  }

  PartitionParams params_;
  Zoltan_Struct* zz_ = nullptr;
  std::span<const Vec<D>> x_;
  std::span<const std::uint64_t> id_;
  std::span<const double> weight_;
};

}  // namespace rsph::mpi
