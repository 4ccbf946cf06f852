//! Probes attached to the run loop (`crate::run::Probe`): one file each.
//! Outputs: particle files, the checkpoint ring, event frames, a replay's
//! checks. Verification checks: the surge front, the decay of an initial
//! flow mode, the sloshing tank, the sound wave, the energy the motion gains, Brackbill's ringing test, and in mixtures the drag
//! decay, the drag layer, Darcy's column, Terzaghi's consolidation, the
//! free surface, and the mixture's rows and conservation.

pub mod checkpoint_ring;
pub mod darcy;
pub mod drag_decay;
pub mod drag_layer;
pub mod energy_gain;
pub mod event_frames;
pub mod mixture_conservation;
pub mod mixture_rows;
pub mod mixture_scene;
pub mod mode_decay;
pub mod particle_files;
pub mod plant_checkpoint;
pub mod replay;
pub mod ringing;
pub mod slosh;
pub mod sound_wave;
pub mod surface;
pub mod surge_front;
pub mod terzaghi;
