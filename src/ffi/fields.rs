//! The one reader of structs C passes by pointer: a [`CStruct`] is a pointer checked for NULL
//! and alignment, and [`c_field!`] reads one of its fields through a raw place — never the
//! struct as a Rust value, since C may store any integer in an enum field and any byte in a
//! `bool`. Enum fields are read as `int` and checked, bools as a byte.
//!
//! The rule for an enum field holding no value of its enum is decided here, once: in an
//! options struct (`nbhd_*_options`, read with [`CStruct::options`]) it is an option out of
//! range, NBHD_STATUS_INVALID_OPTION naming the option, like any other bad option value; in
//! any other struct (`nbhd_points`, `nbhd_neighborhood_spec`, `nbhd_normals_output`, read with
//! [`CStruct::argument`]) it is NBHD_STATUS_INVALID_ARGUMENT naming `arg->field`.

use std::ffi::c_int;
use std::marker::PhantomData;

use super::args::check_ptr;
use super::enums::CEnum;
use super::status::FfiError;
use crate::error::NbhdError;

/// A pointer to a readable, aligned C struct `T`, whose fields [`c_field!`] reads.
pub(crate) struct CStruct<'a, T> {
    ptr: *const T,
    /// `None` for an options struct, the argument's name otherwise.
    arg: Option<&'static str>,
    _borrow: PhantomData<&'a T>,
}

impl<'a, T> CStruct<'a, T> {
    /// An options struct: `options`, or `defaults` when it is NULL.
    ///
    /// # Safety
    /// `options` must be NULL or point to a `T` readable for `'a`.
    pub(crate) unsafe fn options(options: *const T, defaults: &'a T) -> Result<Self, FfiError> {
        let ptr = if options.is_null() {
            defaults as *const T
        } else {
            check_ptr(options, "options")?;
            options
        };
        Ok(Self {
            ptr,
            arg: None,
            _borrow: PhantomData,
        })
    }

    /// A required argument struct named `arg` (NULL is refused).
    ///
    /// # Safety
    /// `p` must be NULL or point to a `T` readable for `'a`.
    pub(crate) unsafe fn argument(p: *const T, arg: &'static str) -> Result<Self, FfiError> {
        check_ptr(p, arg)?;
        Ok(Self {
            ptr: p,
            arg: Some(arg),
            _borrow: PhantomData,
        })
    }

    /// The struct held in the member at `member` of this struct (an options struct inside an
    /// options struct), read the same way.
    ///
    /// # Safety
    /// `member` must point to a member of type `U` of the struct this `CStruct` points to.
    pub(crate) unsafe fn member<U>(&self, member: *const U) -> CStruct<'a, U> {
        CStruct {
            ptr: member,
            arg: self.arg,
            _borrow: PhantomData,
        }
    }

    /// The pointer, non-NULL, aligned and readable for `'a` (the constructors' contract).
    pub(crate) fn ptr(&self) -> *const T {
        self.ptr
    }

    /// The error for enum field `field` holding `bad` (see the module documentation).
    pub(crate) fn invalid_enum(&self, field: &'static str, bad: BadEnum) -> FfiError {
        let BadEnum { value, enum_name } = bad;
        match self.arg {
            None => NbhdError::InvalidOption {
                name: field,
                reason: format!("{value} is not a value of {enum_name}"),
            }
            .into(),
            Some(arg) => FfiError::InvalidArgument(format!(
                "{arg}->{field} is {value}, not a value of {enum_name}"
            )),
        }
    }
}

/// An `int` found in an enum field that names no value of the enum.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BadEnum {
    value: c_int,
    enum_name: &'static str,
}

/// Reads the enum field at `field` as the `int` C stored there: the variant of `E` it names,
/// or what it holds if it names none.
///
/// # Safety
/// `field` must point to a readable, aligned field of type `E` inside a struct given by C.
pub(crate) unsafe fn read_enum<E: CEnum>(field: *const E) -> Result<E, BadEnum> {
    // SAFETY: the caller guarantees `field` is readable and aligned; `E` has the size of
    // `int` (asserted by `c_enum!`) and at least its alignment, and any bit pattern is a
    // valid `int`.
    let value = unsafe { field.cast::<c_int>().read() };
    E::from_value(value).ok_or(BadEnum {
        value,
        enum_name: E::C_NAME,
    })
}

/// Reads a field of the [`CStruct`] `$s`:
/// - `c_field!(s.f)` a plain field (integer, float, pointer, array of them);
/// - `c_field!(s.f as bool)` a C `bool`, read as a byte (non-zero is true);
/// - `c_field!(s.f as enum)` an enum field, read as `int` and checked: `Err` with the status of
///   the module's rule when it holds no value of its enum.
macro_rules! c_field {
    ($s:ident . $f:ident) => {
        // SAFETY: a `CStruct` points to a readable, aligned struct (its constructors'
        // contract); the field is read through a raw place, not the struct as a value.
        unsafe { std::ptr::addr_of!((*$s.ptr()).$f).read() }
    };
    ($s:ident . $f:ident as bool) => {
        // SAFETY: as for a plain field; the bool is read as a byte, so any value C stored
        // there is sound.
        (unsafe { std::ptr::addr_of!((*$s.ptr()).$f).cast::<u8>().read() } != 0)
    };
    ($s:ident . $f:ident as enum) => {
        // SAFETY: as for a plain field; the enum is read as `int` and checked.
        unsafe { $crate::ffi::fields::read_enum(std::ptr::addr_of!((*$s.ptr()).$f)) }
            .map_err(|bad| $s.invalid_enum(stringify!($f), bad))
    };
}
pub(crate) use c_field;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffi::{nbhd_build_options, nbhd_points, nbhd_scalar_type};

    #[test]
    fn an_enum_out_of_range_is_an_option_or_an_argument_by_its_struct() {
        let mut o = std::mem::MaybeUninit::new(nbhd_build_options::from(
            crate::tree::BuildOptions::default(),
        ));
        let p = o.as_mut_ptr();
        // SAFETY: writes an int into the int-sized enum field, as C may; the memory is read
        // again only field by field through `CStruct`.
        unsafe {
            std::ptr::addr_of_mut!((*p).median)
                .cast::<c_int>()
                .write(99)
        };
        let defaults = nbhd_build_options::from(crate::tree::BuildOptions::default());
        // SAFETY: `p` points to a live, aligned nbhd_build_options.
        let s = unsafe { CStruct::options(p.cast_const(), &defaults) }.unwrap();
        let e = c_field!(s.median as enum).unwrap_err();
        assert_eq!(e.status(), crate::ffi::nbhd_status::InvalidOption);
        assert_eq!(
            e.to_string(),
            "option median: 99 is not a value of nbhd_median_algorithm"
        );
        let mut pts = std::mem::MaybeUninit::new(nbhd_points {
            data: std::ptr::null(),
            count: 0,
            dim: 3,
            stride: 0,
            scalar_type: nbhd_scalar_type::F32,
        });
        let q = pts.as_mut_ptr();
        // SAFETY: as above.
        unsafe {
            std::ptr::addr_of_mut!((*q).scalar_type)
                .cast::<c_int>()
                .write(7)
        };
        // SAFETY: `q` points to a live, aligned nbhd_points.
        let s = unsafe { CStruct::argument(q.cast_const(), "points") }.unwrap();
        let e = c_field!(s.scalar_type as enum).unwrap_err();
        assert_eq!(e.status(), crate::ffi::nbhd_status::InvalidArgument);
        assert_eq!(
            e.to_string(),
            "points->scalar_type is 7, not a value of nbhd_scalar_type"
        );
    }
}
