//! DDS encoding (the `ddsfile` crate): a DX10 header (`DXGI_FORMAT_…_FLOAT`), a 2D texture,
//! one mip level, one array layer, alpha mode unknown (the channels are data, not colour).
//! Texel data follows the headers row by row, first row first, little-endian floats.

use ddsfile::{AlphaMode, D3D10ResourceDimension, Dds, DxgiFormat, NewDxgiParams};

use super::{Bits, Table};

/// The DXGI format for `channels` float channels (2 or 4) at `bits` per channel.
pub fn dxgi_format(bits: Bits, channels: usize) -> Option<DxgiFormat> {
    match (bits, channels) {
        (Bits::Half, 2) => Some(DxgiFormat::R16G16_Float),
        (Bits::Float, 2) => Some(DxgiFormat::R32G32_Float),
        (Bits::Half, 4) => Some(DxgiFormat::R16G16B16A16_Float),
        (Bits::Float, 4) => Some(DxgiFormat::R32G32B32A32_Float),
        _ => None,
    }
}

/// Encodes `table` as a DDS file in memory.
pub fn encode(table: &Table, bits: Bits) -> Result<Vec<u8>, String> {
    let format = dxgi_format(bits, table.channels.len())
        .ok_or_else(|| format!("no DXGI float format has {} channels", table.channels.len()))?;
    let mut dds = Dds::new_dxgi(NewDxgiParams {
        height: table.height as u32,
        width: table.width as u32,
        depth: None,
        format,
        mipmap_levels: None,
        array_layers: None,
        caps2: None,
        is_cubemap: false,
        resource_dimension: D3D10ResourceDimension::Texture2D,
        alpha_mode: AlphaMode::Unknown,
    })
    .map_err(|e| e.to_string())?;
    let texels = table.texel_bytes(bits);
    if dds.data.len() != texels.len() {
        return Err(format!(
            "ddsfile expects {} bytes of texels, the table has {}",
            dds.data.len(),
            texels.len()
        ));
    }
    dds.data = texels;
    let mut bytes = Vec::new();
    dds.write(&mut bytes).map_err(|e| e.to_string())?;
    Ok(bytes)
}
