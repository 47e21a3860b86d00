//! The carried arrays (`simulation::carried_state`) in a checkpoint: written in the list's
//! order, an optional array after a flag that says whether the run holds it, and read back as
//! the format version that wrote them kept them.

use super::checkpoint_bytes::{Reader, Writer};
use crate::simulation::carried_state::{Carried, VisitCarried};
use crate::simulation::particle_array::ParticleArray;
use coil_kernels::Real;
use std::marker::PhantomData;

/// Writes the first `n` particles of each carried array, an optional array after a flag that
/// says whether the run holds it.
pub(super) struct WriteCarried<'w, R> {
    pub(super) w: &'w mut Writer,
    pub(super) n: usize,
    pub(super) real: PhantomData<R>,
}

impl<'a, R: Real> VisitCarried<&'a [ParticleArray<f64>], &'a [ParticleArray<R>], &'a [ParticleArray<u32>]>
    for WriteCarried<'_, R>
{
    fn wide(&mut self, _: Carried, components: &'a [ParticleArray<f64>]) {
        for c in components {
            self.w.f64s(&c[..self.n]);
        }
    }
    fn real(&mut self, _: Carried, components: &'a [ParticleArray<R>]) {
        for c in components {
            self.w.reals(&c[..self.n]);
        }
    }
    fn index(&mut self, _: Carried, components: &'a [ParticleArray<u32>]) {
        for c in components {
            for &id in &c[..self.n] {
                self.w.u32(id);
            }
        }
    }
    fn real_where(&mut self, array: Carried, components: Option<&'a [ParticleArray<R>]>) {
        self.w.u8(u8::from(components.is_some()));
        if let Some(components) = components {
            self.real(array, components);
        }
    }
}

/// Reads each carried array back as [`WriteCarried`] wrote it in format `version`: an optional
/// array the version did not keep is absent. The first error stops the reading.
pub(super) struct ReadCarried<'b, R> {
    pub(super) r: Reader<'b>,
    pub(super) n: usize,
    pub(super) real_bytes: usize,
    pub(super) version: u32,
    pub(super) result: Result<(), String>,
    pub(super) real: PhantomData<R>,
}

impl<R> ReadCarried<'_, R> {
    /// Each component's `n` entries of `width` bytes, decoded by `from`; an array the format
    /// version did not keep keeps what the run set up.
    fn read<T>(&mut self, array: Carried, components: &mut [ParticleArray<T>], width: usize, from: impl Fn(&[u8]) -> T) {
        if self.version < array.since {
            return;
        }
        for c in components {
            if self.result.is_err() {
                return;
            }
            match self.r.take(self.n * width, array.what) {
                Ok(bytes) => {
                    for (v, b) in c[..self.n].iter_mut().zip(bytes.chunks_exact(width)) {
                        *v = from(b);
                    }
                }
                Err(e) => self.result = Err(e),
            }
        }
    }
}

impl<'a, R: Real> VisitCarried<&'a mut [ParticleArray<f64>], &'a mut [ParticleArray<R>], &'a mut [ParticleArray<u32>]>
    for ReadCarried<'_, R>
{
    fn wide(&mut self, array: Carried, components: &'a mut [ParticleArray<f64>]) {
        self.read(array, components, 8, |b| f64::from_le_bytes(b.try_into().expect("8 bytes")));
    }
    fn real(&mut self, array: Carried, components: &'a mut [ParticleArray<R>]) {
        let real = |b: &[u8]| match b.len() {
            4 => R::from_f64(f32::from_le_bytes(b.try_into().expect("4 bytes")) as f64),
            _ => R::from_f64(f64::from_le_bytes(b.try_into().expect("8 bytes"))),
        };
        self.read(array, components, self.real_bytes, real);
    }
    fn index(&mut self, array: Carried, components: &'a mut [ParticleArray<u32>]) {
        self.read(array, components, 4, |b| u32::from_le_bytes(b.try_into().expect("4 bytes")));
    }
    fn real_where(&mut self, array: Carried, components: Option<&'a mut [ParticleArray<R>]>) {
        if self.result.is_err() {
            return;
        }
        // A version before the array's kept none, and has no flag for it.
        let held = match self.version >= array.since {
            true => self.r.u8(array.what).map(|flag| flag == 1),
            false => Ok(false),
        };
        match (components, held) {
            (_, Err(e)) => self.result = Err(e),
            (Some(components), Ok(true)) => self.real(array, components),
            (None, Ok(false)) => {}
            (Some(_), Ok(false)) => self.result = Err(format!("holds none of {}, which the scene's run carries", array.what)),
            (None, Ok(true)) => self.result = Err(format!("holds {}, which the scene's run does not carry", array.what)),
        }
    }
}
