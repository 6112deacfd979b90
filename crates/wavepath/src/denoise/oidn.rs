//! The Open Image Denoise C API (2.x, `OpenImageDenoise/oidn.h`) as function pointers resolved
//! once from a library loaded at run time, and owners of its buffers and filters that release
//! them when dropped. Only the calls the denoiser makes are here.

use std::ffi::{CStr, c_char, c_int, c_void};

use libloading::Library;

/// `OIDNDevice`, `OIDNBuffer`, `OIDNFilter`: opaque handles.
pub type RawDevice = *mut c_void;
type RawBuffer = *mut c_void;
type RawFilter = *mut c_void;

/// `OIDN_DEVICE_TYPE_CPU` (C enums are `int`-sized on every ABI OIDN ships for).
pub const DEVICE_TYPE_CPU: c_int = 1;
/// `OIDN_FORMAT_FLOAT3`.
const FORMAT_FLOAT3: c_int = 3;
/// `OIDN_ERROR_NONE`.
const ERROR_NONE: c_int = 0;

/// Declares `Api`, one field per C function, and `Api::resolve`, which looks every one up.
macro_rules! api {
    ($($field:ident = $symbol:literal: fn($($arg:ty),*) $(-> $ret:ty)?;)*) => {
        /// The C functions, resolved from one loaded library.
        pub struct Api {
            $(pub $field: unsafe extern "C" fn($($arg),*) $(-> $ret)?,)*
        }

        impl Api {
            /// Every function of the API, or the name of the first symbol `library` lacks.
            ///
            /// # Safety
            /// `library` must be Open Image Denoise 2.x, whose symbols of these names have
            /// these C signatures, and it must stay loaded for as long as the `Api` is used.
            pub unsafe fn resolve(library: &Library) -> Result<Api, &'static str> {
                Ok(Api {
                    $($field: {
                        // SAFETY: the caller guarantees the symbol has this signature; the
                        // pointer is copied out and used only while the library stays loaded.
                        let symbol = unsafe {
                            library.get::<unsafe extern "C" fn($($arg),*) $(-> $ret)?>(
                                concat!($symbol, "\0").as_bytes(),
                            )
                        };
                        *symbol.map_err(|_| $symbol)?
                    },)*
                })
            }
        }
    };
}

api! {
    new_device = "oidnNewDevice": fn(c_int) -> RawDevice;
    commit_device = "oidnCommitDevice": fn(RawDevice);
    release_device = "oidnReleaseDevice": fn(RawDevice);
    get_device_error = "oidnGetDeviceError": fn(RawDevice, *mut *const c_char) -> c_int;
    new_buffer = "oidnNewBuffer": fn(RawDevice, usize) -> RawBuffer;
    write_buffer = "oidnWriteBuffer": fn(RawBuffer, usize, usize, *const c_void);
    read_buffer = "oidnReadBuffer": fn(RawBuffer, usize, usize, *mut c_void);
    release_buffer = "oidnReleaseBuffer": fn(RawBuffer);
    new_filter = "oidnNewFilter": fn(RawDevice, *const c_char) -> RawFilter;
    set_filter_image = "oidnSetFilterImage": fn(RawFilter, *const c_char, RawBuffer, c_int, usize, usize, usize, usize, usize);
    set_filter_bool = "oidnSetFilterBool": fn(RawFilter, *const c_char, bool);
    commit_filter = "oidnCommitFilter": fn(RawFilter);
    execute_filter = "oidnExecuteFilter": fn(RawFilter);
    release_filter = "oidnReleaseFilter": fn(RawFilter);
}

/// A committed device. The handle is only a pointer to OIDN's object; OIDN's API is
/// thread-safe, so it may be used from any thread (the denoiser still serialises its use).
pub struct Device(pub RawDevice);

// SAFETY: an OIDN device is not tied to the thread that created it: every API call on it is
// thread-safe (OIDN's documentation), and the denoiser keeps it behind a mutex anyway.
unsafe impl Send for Device {}

impl Api {
    /// The error stored for this thread on `device` (null: errors not tied to a device, such as
    /// a failed `oidnNewDevice`), cleared by reading it; OIDN's message on one line.
    pub fn take_error(&self, device: RawDevice) -> Option<String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: `device` is null or a live device of this library; `message` is a valid place
        // for the pointer OIDN writes.
        let code = unsafe { (self.get_device_error)(device, &mut message) };
        if code == ERROR_NONE {
            return None;
        }
        let text = if message.is_null() {
            String::new()
        } else {
            // SAFETY: OIDN returns a NUL-terminated string that stays valid until the next API
            // call on this thread; it is copied out at once.
            unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
        };
        let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
        Some(if text.is_empty() { format!("error code {code}") } else { text })
    }

    /// `Ok` when `device` holds no error, else OIDN's message after `doing`.
    pub fn check(&self, device: RawDevice, doing: &str) -> Result<(), String> {
        match self.take_error(device) {
            None => Ok(()),
            Some(message) => Err(format!("{doing}: {message}")),
        }
    }
}

/// A buffer of `len` floats in the device's memory, released when dropped.
pub struct Buffer<'a> {
    api: &'a Api,
    raw: RawBuffer,
    len: usize,
}

impl<'a> Buffer<'a> {
    /// A new buffer holding `data`.
    pub fn with_data(api: &'a Api, device: &Device, data: &[f32]) -> Result<Buffer<'a>, String> {
        let bytes = std::mem::size_of_val(data);
        // SAFETY: `device` is a live, committed device of this library.
        let raw = unsafe { (api.new_buffer)(device.0, bytes) };
        api.check(device.0, "cannot allocate a buffer")?;
        if raw.is_null() {
            return Err("cannot allocate a buffer".into());
        }
        let buffer = Buffer { api, raw, len: data.len() };
        // SAFETY: the buffer holds `bytes` bytes and `data` is that many readable bytes.
        unsafe { (api.write_buffer)(raw, 0, bytes, data.as_ptr().cast()) };
        api.check(device.0, "cannot fill a buffer")?;
        Ok(buffer)
    }

    /// The buffer's floats.
    pub fn read(&self, device: &Device) -> Result<Vec<f32>, String> {
        let mut out = vec![0.0f32; self.len];
        // SAFETY: the buffer holds `len` floats and `out` has room for exactly that many.
        unsafe { (self.api.read_buffer)(self.raw, 0, std::mem::size_of_val(&out[..]), out.as_mut_ptr().cast()) };
        self.api.check(device.0, "cannot read the result")?;
        Ok(out)
    }
}

impl Drop for Buffer<'_> {
    fn drop(&mut self) {
        // SAFETY: `raw` is a live buffer this owner holds the only reference of; a filter that
        // uses it holds its own reference, so releasing first is allowed by OIDN.
        unsafe { (self.api.release_buffer)(self.raw) };
    }
}

/// An "RT" filter, released when dropped.
pub struct Filter<'a> {
    api: &'a Api,
    raw: RawFilter,
}

impl<'a> Filter<'a> {
    /// A new "RT" (ray tracing) filter on `device`.
    pub fn rt(api: &'a Api, device: &Device) -> Result<Filter<'a>, String> {
        // SAFETY: `device` is live; the type name is a NUL-terminated string.
        let raw = unsafe { (api.new_filter)(device.0, c"RT".as_ptr()) };
        api.check(device.0, "cannot create the RT filter")?;
        if raw.is_null() {
            return Err("cannot create the RT filter".into());
        }
        Ok(Filter { api, raw })
    }

    /// Binds the image `name` ("color", "albedo", "normal", "output") to `buffer`: packed RGB
    /// floats, `width` by `height`, rows in order.
    pub fn set_image(&self, name: &CStr, buffer: &Buffer<'_>, width: usize, height: usize) {
        assert_eq!(buffer.len, width * height * 3, "the image's buffer has its size");
        // SAFETY: filter and buffer are live objects of one device; the buffer holds exactly a
        // packed `width` x `height` FLOAT3 image (checked above); strides 0 mean packed.
        unsafe {
            (self.api.set_filter_image)(self.raw, name.as_ptr(), buffer.raw, FORMAT_FLOAT3, width, height, 0, 0, 0)
        };
    }

    pub fn set_bool(&self, name: &CStr, value: bool) {
        // SAFETY: the filter is live; `name` is NUL-terminated.
        unsafe { (self.api.set_filter_bool)(self.raw, name.as_ptr(), value) };
    }

    /// Commits the parameters and runs the filter to completion.
    pub fn run(&self, device: &Device, what: &str) -> Result<(), String> {
        // SAFETY: the filter is live and its images are bound to live buffers of the device.
        unsafe { (self.api.commit_filter)(self.raw) };
        self.api.check(device.0, &format!("cannot set up {what}"))?;
        // SAFETY: as above; `oidnExecuteFilter` is synchronous, so the buffers are done with
        // when it returns.
        unsafe { (self.api.execute_filter)(self.raw) };
        self.api.check(device.0, &format!("{what} failed"))
    }
}

impl Drop for Filter<'_> {
    fn drop(&mut self) {
        // SAFETY: `raw` is a live filter this owner holds the only reference of.
        unsafe { (self.api.release_filter)(self.raw) };
    }
}
