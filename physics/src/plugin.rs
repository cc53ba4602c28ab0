//! The one place that touches MuJoCo's plugin FFI: registers `autobio.detent` (passive force) and
//! `autobio.thread` (SDF) with `mjp_registerPlugin`, once per process, and keeps each instance's
//! state in `mjData::plugin_data`. Everything else uses [`register`] and [`instance_errors`].
//!
//! MuJoCo ends the process on errors raised inside plugin callbacks, so nothing here fails inside a
//! callback: a detent whose joint is unusable records why and applies no force, and
//! [`instance_errors`] reports it to the caller after the data is made.

use crate::detent::Detent;
use crate::thread::{ATTRIBUTES, Thread};
use mujoco_rs::mujoco_c::{
    mj_getPluginConfig, mj_name2id, mjData, mjModel, mjp_defaultPlugin, mjp_registerPlugin,
    mjpPlugin, mjtJoint, mjtNum, mjtObj, mjtPluginCapabilityBit,
};
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::sync::OnceLock;

pub(crate) const DETENT: &str = "autobio.detent";
pub(crate) const THREAD: &str = "autobio.thread";

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PluginError {
    #[error("mujoco refused to register plugin `{0}`")]
    Register(&'static str),
}

/// Registry slot of the detent plugin (the one whose instances can report errors).
#[derive(Clone, Copy, Debug)]
struct Slots {
    detent: c_int,
}

static SLOTS: OnceLock<Result<Slots, PluginError>> = OnceLock::new();

#[repr(transparent)]
struct Names<const N: usize>([*const c_char; N]);
// SAFETY: the pointers are to 'static C string literals, never written.
unsafe impl<const N: usize> Sync for Names<N> {}

static DETENT_ATTRS: Names<4> = Names([
    c"joint".as_ptr(),
    c"n".as_ptr(),
    c"stiffness".as_ptr(),
    c"damping".as_ptr(),
]);
static THREAD_ATTRS: Names<5> = Names([
    c"radius".as_ptr(),
    c"gauge".as_ptr(),
    c"pitch".as_ptr(),
    c"low".as_ptr(),
    c"high".as_ptr(),
]);

/// Registers both plugins (idempotent, thread-safe). Call before compiling a model that uses them.
pub fn register() -> Result<(), PluginError> {
    SLOTS.get_or_init(register_now).clone().map(|_| ())
}

fn register_now() -> Result<Slots, PluginError> {
    // SAFETY: mjp_defaultPlugin fills a zeroed struct; every pointer stored is 'static and every
    // callback has the signature the struct declares.
    unsafe {
        let mut p: mjpPlugin = std::mem::zeroed();
        mjp_defaultPlugin(&mut p);
        p.name = c"autobio.detent".as_ptr();
        p.nattribute = DETENT_ATTRS.0.len() as c_int;
        p.attributes = DETENT_ATTRS.0.as_ptr();
        p.capabilityflags = mjtPluginCapabilityBit::mjPLUGIN_PASSIVE as c_int;
        p.nstate = Some(no_state);
        p.init = Some(detent_init);
        p.destroy = Some(destroy::<DetentInstance>);
        p.copy = Some(copy::<DetentInstance>);
        p.reset = Some(reset);
        p.compute = Some(detent_compute);
        let detent = mjp_registerPlugin(&p);
        if detent < 0 {
            return Err(PluginError::Register(DETENT));
        }

        let mut p: mjpPlugin = std::mem::zeroed();
        mjp_defaultPlugin(&mut p);
        p.name = c"autobio.thread".as_ptr();
        p.nattribute = THREAD_ATTRS.0.len() as c_int;
        p.attributes = THREAD_ATTRS.0.as_ptr();
        p.capabilityflags = mjtPluginCapabilityBit::mjPLUGIN_SDF as c_int;
        p.nstate = Some(no_state);
        p.init = Some(thread_init);
        p.destroy = Some(destroy::<Thread>);
        p.copy = Some(copy::<Thread>);
        p.reset = Some(reset);
        p.compute = Some(no_compute);
        p.sdf_distance = Some(thread_distance);
        p.sdf_gradient = Some(thread_gradient);
        p.sdf_staticdistance = Some(thread_static_distance);
        p.sdf_attribute = Some(thread_attributes);
        p.sdf_aabb = Some(thread_aabb);
        let thread = mjp_registerPlugin(&p);
        if thread < 0 {
            return Err(PluginError::Register(THREAD));
        }
        Ok(Slots { detent })
    }
}

/// Problems found when instances were initialised for `data` (e.g. a detent naming no joint).
pub fn instance_errors(model: &mjModel, data: &mjData) -> Vec<String> {
    let Some(Ok(slots)) = SLOTS.get() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for i in 0..model.nplugin as usize {
        // SAFETY: `plugin` and `plugin_data` have `nplugin` entries.
        let (slot, ptr) = unsafe { (*model.plugin.add(i), *data.plugin_data.add(i)) };
        if slot == slots.detent && ptr != 0 {
            // SAFETY: detent instances store a Box<DetentInstance> (see detent_init).
            if let DetentInstance::Invalid(why) = unsafe { &*(ptr as *const DetentInstance) } {
                out.push(format!("detent instance {i}: {why}"));
            }
        }
    }
    out
}

/// The config value of `key` for plugin instance `instance`, if set.
unsafe fn config(m: *const mjModel, instance: c_int, key: &CStr) -> Option<String> {
    // SAFETY: MuJoCo returns NULL or a NUL-terminated string owned by the model.
    unsafe {
        let v = mj_getPluginConfig(m, instance, key.as_ptr());
        if v.is_null() {
            return None;
        }
        let s = CStr::from_ptr(v).to_string_lossy().into_owned();
        (!s.is_empty()).then_some(s)
    }
}

unsafe fn config_f64(m: *const mjModel, instance: c_int, key: &CStr, default: f64) -> Option<f64> {
    // SAFETY: as `config`.
    match unsafe { config(m, instance, key) } {
        None => Some(default),
        Some(s) => s.trim().parse().ok(),
    }
}

unsafe extern "C" fn no_state(_m: *const mjModel, _instance: c_int) -> c_int {
    0
}

unsafe extern "C" fn reset(
    _m: *const mjModel,
    _state: *mut mjtNum,
    _data: *mut c_void,
    _instance: c_int,
) {
}

unsafe extern "C" fn no_compute(_m: *const mjModel, _d: *mut mjData, _i: c_int, _bit: c_int) {}

unsafe fn store<T>(d: *mut mjData, instance: c_int, value: T) {
    // SAFETY: plugin_data has an entry per instance; ownership passes to `destroy`.
    unsafe { *(*d).plugin_data.add(instance as usize) = Box::into_raw(Box::new(value)) as usize };
}

unsafe extern "C" fn destroy<T>(d: *mut mjData, instance: c_int) {
    // SAFETY: the entry is 0 or a Box<T> made by `store`.
    unsafe {
        let slot = (*d).plugin_data.add(instance as usize);
        if *slot != 0 {
            drop(Box::from_raw(*slot as *mut T));
            *slot = 0;
        }
    }
}

unsafe extern "C" fn copy<T: Clone>(
    dest: *mut mjData,
    _m: *const mjModel,
    src: *const mjData,
    instance: c_int,
) {
    // SAFETY: the source entry is 0 or a Box<T>; the copy gets its own Box so the two datas never
    // share (or double-free) state.
    unsafe {
        let s = *(*src).plugin_data.add(instance as usize);
        let value = (s != 0).then(|| (*(s as *const T)).clone());
        *(*dest).plugin_data.add(instance as usize) = match value {
            Some(v) => Box::into_raw(Box::new(v)) as usize,
            None => 0,
        };
    }
}

#[derive(Clone, Debug)]
enum DetentInstance {
    Ready {
        qpos: usize,
        dof: usize,
        detent: Detent,
    },
    Invalid(String),
}

unsafe fn detent_instance(m: *const mjModel, instance: c_int) -> DetentInstance {
    // SAFETY: `m` is the model being initialised; indices come from MuJoCo.
    unsafe {
        let Some(joint) = config(m, instance, c"joint") else {
            return DetentInstance::Invalid("no `joint` in the config".into());
        };
        let Ok(cjoint) = CString::new(joint.clone()) else {
            return DetentInstance::Invalid(format!("bad joint name `{joint}`"));
        };
        let id = mj_name2id(m, mjtObj::mjOBJ_JOINT as c_int, cjoint.as_ptr());
        if id < 0 {
            return DetentInstance::Invalid(format!("no joint named `{joint}`"));
        }
        let id = id as usize;
        let jtype = *(*m).jnt_type.add(id);
        if jtype != mjtJoint::mjJNT_HINGE as c_int && jtype != mjtJoint::mjJNT_SLIDE as c_int {
            return DetentInstance::Invalid(format!("joint `{joint}` is not a hinge or slide"));
        }
        if !*(*m).jnt_limited.add(id) {
            return DetentInstance::Invalid(format!("joint `{joint}` has no range"));
        }
        let Some(n) = config(m, instance, c"n")
            .and_then(|s| s.trim().parse::<u32>().ok())
            .filter(|n| *n >= 2)
        else {
            return DetentInstance::Invalid("`n` must be an integer >= 2".into());
        };
        let Some(stiffness) = config_f64(m, instance, c"stiffness", 0.0).filter(|k| *k >= 0.0)
        else {
            return DetentInstance::Invalid("`stiffness` must be a non-negative number".into());
        };
        let Some(damping) = config_f64(m, instance, c"damping", 0.0).filter(|b| *b >= 0.0) else {
            return DetentInstance::Invalid("`damping` must be a non-negative number".into());
        };
        DetentInstance::Ready {
            qpos: *(*m).jnt_qposadr.add(id) as usize,
            dof: *(*m).jnt_dofadr.add(id) as usize,
            detent: Detent {
                lo: *(*m).jnt_range.add(2 * id),
                hi: *(*m).jnt_range.add(2 * id + 1),
                n,
                stiffness,
                damping,
            },
        }
    }
}

unsafe extern "C" fn detent_init(m: *const mjModel, d: *mut mjData, instance: c_int) -> c_int {
    // SAFETY: called by MuJoCo with a valid model and data.
    unsafe {
        let value = detent_instance(m, instance);
        store(d, instance, value);
    }
    0
}

unsafe extern "C" fn detent_compute(
    _m: *const mjModel,
    d: *mut mjData,
    instance: c_int,
    bit: c_int,
) {
    if bit & mjtPluginCapabilityBit::mjPLUGIN_PASSIVE as c_int == 0 {
        return;
    }
    // SAFETY: the entry is a Box<DetentInstance>; qpos/dof were checked against the model.
    unsafe {
        let ptr = *(*d).plugin_data.add(instance as usize);
        if ptr == 0 {
            return;
        }
        if let DetentInstance::Ready { qpos, dof, detent } = &*(ptr as *const DetentInstance) {
            let q = *(*d).qpos.add(*qpos);
            let qd = *(*d).qvel.add(*dof);
            *(*d).qfrc_passive.add(*dof) += detent.force(q, qd);
        }
    }
}

unsafe fn thread_from_config(m: *const mjModel, instance: c_int) -> Thread {
    let defaults = DEFAULT_THREAD.attributes();
    let mut a = defaults;
    for (i, key) in ATTRIBUTES.iter().enumerate() {
        let key = CString::new(*key).expect("attribute names have no NUL");
        // SAFETY: as `config`.
        a[i] = unsafe { config_f64(m, instance, &key, defaults[i]) }.unwrap_or(defaults[i]);
    }
    Thread::from_attributes(&a)
}

/// Used for attributes left unset.
const DEFAULT_THREAD: Thread = Thread {
    radius: 0.01,
    gauge: 0.001,
    pitch: 0.003,
    low: -1.0,
    high: 1.0,
};

unsafe extern "C" fn thread_init(m: *const mjModel, d: *mut mjData, instance: c_int) -> c_int {
    // SAFETY: called by MuJoCo with a valid model and data.
    unsafe {
        let t = thread_from_config(m, instance);
        store(d, instance, t);
    }
    0
}

unsafe fn thread_of<'a>(d: *const mjData, instance: c_int) -> Option<&'a Thread> {
    // SAFETY: the entry is 0 or a Box<Thread> made by thread_init.
    unsafe {
        let ptr = *(*d).plugin_data.add(instance as usize);
        (ptr != 0).then(|| &*(ptr as *const Thread))
    }
}

unsafe extern "C" fn thread_distance(
    point: *const [mjtNum; 3],
    d: *const mjData,
    instance: c_int,
) -> mjtNum {
    // SAFETY: MuJoCo passes a valid point and data.
    unsafe {
        match thread_of(d, instance) {
            Some(t) => t.distance(*point),
            None => DEFAULT_THREAD.distance(*point),
        }
    }
}

unsafe extern "C" fn thread_gradient(
    gradient: *mut [mjtNum; 3],
    point: *const [mjtNum; 3],
    d: *const mjData,
    instance: c_int,
) {
    // SAFETY: MuJoCo passes valid pointers.
    unsafe {
        *gradient = match thread_of(d, instance) {
            Some(t) => t.gradient(*point),
            None => DEFAULT_THREAD.gradient(*point),
        };
    }
}

unsafe fn attrs(attributes: *const mjtNum) -> Thread {
    // SAFETY: MuJoCo passes the array filled by thread_attributes (one value per attribute).
    unsafe {
        let mut a = [0.0; 5];
        for (i, v) in a.iter_mut().enumerate() {
            *v = *attributes.add(i);
        }
        Thread::from_attributes(&a)
    }
}

unsafe extern "C" fn thread_static_distance(
    point: *const [mjtNum; 3],
    attributes: *const mjtNum,
) -> mjtNum {
    // SAFETY: as `attrs`.
    unsafe { attrs(attributes).distance(*point) }
}

unsafe extern "C" fn thread_aabb(aabb: *mut [mjtNum; 6], attributes: *const mjtNum) {
    // SAFETY: as `attrs`.
    unsafe { *aabb = attrs(attributes).aabb() };
}

unsafe extern "C" fn thread_attributes(
    attribute: *mut mjtNum,
    _name: *mut *const c_char,
    value: *mut *const c_char,
) {
    let defaults = DEFAULT_THREAD.attributes();
    // SAFETY: MuJoCo passes arrays with one entry per declared attribute, values NUL-terminated
    // (empty when unset).
    unsafe {
        for (i, default) in defaults.iter().enumerate() {
            let v = *value.add(i);
            let parsed = if v.is_null() {
                None
            } else {
                CStr::from_ptr(v)
                    .to_str()
                    .ok()
                    .and_then(|s| s.trim().parse().ok())
            };
            *attribute.add(i) = parsed.unwrap_or(*default);
        }
    }
}
