//! The GPU as the engine's kernel path: the engine defines [`KernelPath`] and its
//! ensembles, the GPU implements them here (the engine imports nothing from the GPU).

use crate::engine::{dynamic, BatchTables, KernelPath, ResidentStatic};
use crate::model::Model;

/// The WGSL kernels on the shared GPU context, resident per batch
/// ([`super::batch::GpuStatic`]).
pub struct GpuPath(pub &'static super::GpuContext);

impl<T: super::contact::GpuReal> KernelPath<T> for GpuPath {
    fn max_batch(&self, model: &Model) -> usize {
        super::batch::max_variants(self.0, model, std::mem::size_of::<T>())
    }
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<T>,
    ) -> Result<Box<dyn ResidentStatic<T> + 'a>, crate::error::SystemError> {
        super::batch::GpuStatic::new(self.0, model, tables)
            .map(|e| Box::new(e) as Box<dyn ResidentStatic<T> + 'a>)
            .map_err(crate::error::SystemError::from)
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<T>,
        dynamic: &dynamic::DynamicTables<T>,
    ) -> Result<Box<dyn dynamic::ResidentDynamic<T> + 'a>, crate::error::SystemError> {
        super::batch::GpuDynamic::new(self.0, model, tables, dynamic)
            .map(|e| Box::new(e) as Box<dyn dynamic::ResidentDynamic<T> + 'a>)
            .map_err(crate::error::SystemError::from)
    }
}
