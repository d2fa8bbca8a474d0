//! [`Layer`]s as JavaScript objects, `{ name, width, height, kind, data }` with `data` a typed
//! array (`Uint8Array` for `rgba` and `mask`, `Float32Array` for `levels`, `Uint16Array` for
//! `sixteen`, `Float64Array` for `numbers`), whose buffers the worker hands to the page without
//! copying.

use js_sys::{Array, Float32Array, Float64Array, Object, Reflect, Uint8Array, Uint16Array};
use wasm_bindgen::{JsCast, JsValue};

use crate::transfer::{Layer, LayerData};

/// The layers as an array of objects.
pub(super) fn to_js(layers: Vec<Layer>) -> Array {
    let array = Array::new();
    for layer in layers {
        let object = Object::new();
        let (kind, data): (&str, JsValue) = match &layer.data {
            LayerData::Rgba(bytes) => ("rgba", Uint8Array::from(bytes.as_slice()).into()),
            LayerData::Levels(levels) => ("levels", Float32Array::from(levels.as_slice()).into()),
            LayerData::Sixteen(values) => ("sixteen", Uint16Array::from(values.as_slice()).into()),
            LayerData::Numbers(numbers) => ("numbers", Float64Array::from(numbers.as_slice()).into()),
            LayerData::Mask(mask) => ("mask", Uint8Array::from(mask.as_slice()).into()),
        };
        for (key, value) in [
            ("name", JsValue::from(layer.name.as_str())),
            ("width", layer.width.into()),
            ("height", layer.height.into()),
            ("kind", kind.into()),
            ("data", data),
        ] {
            let _ = Reflect::set(&object, &key.into(), &value);
        }
        array.push(&object);
    }
    array
}

/// The layers back from an array of such objects; what is not such an object is an error.
pub(super) fn from_js(array: &Array) -> Result<Vec<Layer>, String> {
    array
        .iter()
        .map(|object| {
            let field = |key: &str| Reflect::get(&object, &key.into()).unwrap_or(JsValue::UNDEFINED);
            let name = field("name").as_string().ok_or("a world layer without a name")?;
            let number = |key: &str| {
                field(key).as_f64().filter(|n| n.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(n))
            };
            let (Some(width), Some(height)) = (number("width"), number("height")) else {
                return Err(format!("the world layer `{name}` has no size"));
            };
            let data = field("data");
            let data = match field("kind").as_string().as_deref() {
                Some("rgba") => data.dyn_into::<Uint8Array>().map(|a| LayerData::Rgba(a.to_vec())),
                Some("levels") => data.dyn_into::<Float32Array>().map(|a| LayerData::Levels(a.to_vec())),
                Some("sixteen") => data.dyn_into::<Uint16Array>().map(|a| LayerData::Sixteen(a.to_vec())),
                Some("numbers") => data.dyn_into::<Float64Array>().map(|a| LayerData::Numbers(a.to_vec())),
                Some("mask") => data.dyn_into::<Uint8Array>().map(|a| LayerData::Mask(a.to_vec())),
                _ => return Err(format!("the world layer `{name}` is of no known kind")),
            }
            .map_err(|_| format!("the world layer `{name}` holds the wrong kind of array"))?;
            Ok(Layer { name, width: width as u32, height: height as u32, data })
        })
        .collect()
}
