//! The GPU as the engine's kernel path: the engine defines [`KernelPath`] and its
//! ensembles, the GPU implements them here (the engine imports nothing from the GPU).

use crate::engine::{dynamic, Ensemble, EnsembleTables, KernelPath};
use crate::model::Model;

/// The WGSL kernels on the shared GPU context, resident per chunk
/// ([`super::ensemble::GpuEnsemble`]).
pub struct GpuPath(pub &'static super::GpuContext);

impl<T: super::contact::GpuReal> KernelPath<T> for GpuPath {
    fn max_chunk(&self, model: &Model) -> usize {
        super::ensemble::max_variants(self.0, model, std::mem::size_of::<T>())
    }
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
    ) -> Result<Box<dyn Ensemble<T> + 'a>, crate::error::SystemError> {
        super::ensemble::GpuEnsemble::new(self.0, model, tables)
            .map(|e| Box::new(e) as Box<dyn Ensemble<T> + 'a>)
            .map_err(crate::error::SystemError::from)
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
        dynamic: &dynamic::DynamicTables<T>,
    ) -> Result<Box<dyn dynamic::DynamicEnsemble<T> + 'a>, crate::error::SystemError> {
        super::ensemble::GpuDynamic::new(self.0, model, tables, dynamic)
            .map(|e| Box::new(e) as Box<dyn dynamic::DynamicEnsemble<T> + 'a>)
            .map_err(crate::error::SystemError::from)
    }
}
