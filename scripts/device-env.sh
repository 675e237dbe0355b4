# Sourced on a machine that has no OpenMPI of its own: points the loader, OpenMPI and PMIx at device-carry/
# (made by scripts/device-carry.sh). OPAL_PREFIX moves every OpenMPI folder under device-carry/root/usr; PMIx
# is told where its plugins are; shared memory within the node (vader) is the only transport a one-node run needs.
carry=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/device-carry
export PATH="$carry/bin:$PATH"
export LD_LIBRARY_PATH="$carry/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export OPAL_PREFIX="$carry/root/usr"
export OPAL_SYSCONFDIR="$carry/root/etc/openmpi"
export PMIX_MCA_mca_base_component_path="$carry/root/usr/lib/x86_64-linux-gnu/pmix2/lib/pmix"
export OMPI_MCA_btl=self,vader OMPI_MCA_pml=ob1 OMPI_MCA_mtl='^ofi,psm,psm2' OMPI_MCA_osc='^ucx'
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
