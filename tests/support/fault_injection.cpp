// A fault injector for the tests of dying ranks (tests/harness/mpi_test.cpp), loaded into each rank with LD_PRELOAD
// (`mpirun -x LD_PRELOAD=... -x CCDBENCH_FAULT=...`): it ends one rank the way a kill does (_exit: no unwinding, no
// flush, no MPI_Finalize) at a point the test chooses, so that ccdbench itself carries no test hook.
//
// CCDBENCH_FAULT="RANK:EVENT:N" ends the rank whose OMPI_COMM_WORLD_RANK is RANK
//   - EVENT = message: when it has received its N-th message (MPI's profiling interface: this MPI_Recv calls
//     PMPI_Recv, the library's own);
//   - EVENT = cell: right after its N-th rename into a folder named cells (a finished cell written whole,
//     harness/cell_store.cpp through datasets/atomic_file.cpp).
// It says so on stderr first, naming the rank, so that a test can tell its fault from any other failure.

#include <mpi.h>

#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

struct Fault {
  int rank = -1;
  std::string event;
  long after = 0;
};

/// The fault this process is to suffer, or none (rank -1).
const Fault& fault() {
  static const Fault parsed = [] {
    Fault f;
    const char* spec = std::getenv("CCDBENCH_FAULT");
    const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
    if (spec == nullptr || rank == nullptr) return f;
    char event[16] = {};
    int target = -1;
    long after = 0;
    if (std::sscanf(spec, "%d:%15[a-z]:%ld", &target, event, &after) != 3 || target != std::atoi(rank)) return f;
    f.rank = target;
    f.event = event;
    f.after = after;
    return f;
  }();
  return parsed;
}

/// Counts one `event`; ends the process once the count reaches the fault's N.
void count(const char* event) {
  static std::atomic<long> seen{0};
  const Fault& f = fault();
  if (f.rank < 0 || f.event != event) return;
  const long now = ++seen;
  if (now < f.after) return;
  std::fprintf(stderr, "fault injection: rank %d ends at its %s number %ld (CCDBENCH_FAULT)\n", f.rank, event, now);
  std::fflush(stderr);
  ::_exit(86);
}

}  // namespace

extern "C" int MPI_Recv(void* buffer, int count_of, MPI_Datatype type, int source, int tag, MPI_Comm comm, MPI_Status* status) {
  const int result = PMPI_Recv(buffer, count_of, type, source, tag, comm, status);
  count("message");
  return result;
}

extern "C" int rename(const char* from, const char* to) {
  using Rename = int (*)(const char*, const char*);
  static const auto next = reinterpret_cast<Rename>(::dlsym(RTLD_NEXT, "rename"));
  const int result = next(from, to);
  const std::string target = to;
  const std::size_t slash = target.rfind('/');
  const bool into_cells = slash != std::string::npos && slash >= 5 && target.compare(slash - 5, 5, "cells") == 0;
  if (result == 0 && into_cells) count("cell");
  return result;
}
