//! A minimal KTX 2.0 writer (Khronos KTX File Format Specification 2.0): one 2D image, one
//! mip level, no array layers, no cube faces, no supercompression, one Basic Data Format
//! Descriptor block (Khronos Data Format Specification 1.3), and a `KTXwriter` key.
//!
//! File layout, all integers little-endian, in the order the specification fixes:
//!
//! | bytes | what |
//! | --- | --- |
//! | 0..12 | identifier `«KTX 20»\r\n\x1A\n` |
//! | 12..48 | vkFormat, typeSize, pixelWidth, pixelHeight, pixelDepth = 0, layerCount = 0, faceCount = 1, levelCount = 1, supercompressionScheme = 0 |
//! | 48..80 | index: dfdByteOffset, dfdByteLength, kvdByteOffset, kvdByteLength (u32); sgdByteOffset = 0, sgdByteLength = 0 (u64) |
//! | 80..104 | level index for level 0: byteOffset, byteLength, uncompressedByteLength (u64) |
//! | 104.. | DFD: dfdTotalSize (u32), then the Basic block (24 + 16 × samples bytes) |
//! | | key/value data: `KTXwriter` entry, padded to 4 bytes |
//! | | padding to a multiple of lcm(texel size, 4), then the texels, first row first |

use super::{Bits, Table};

/// `«KTX 20»\r\n\x1A\n`
pub const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

/// The Vulkan formats the LUTs use (values from `VkFormat`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum VkFormat {
    R16G16Sfloat = 83,
    R16G16B16A16Sfloat = 97,
    R32G32Sfloat = 103,
    R32G32B32A32Sfloat = 109,
}

impl VkFormat {
    /// The format for `channels` (2, else 4) signed floats of `bits` bits.
    pub fn of(bits: Bits, channels: usize) -> VkFormat {
        match (bits, channels) {
            (Bits::Half, 2) => VkFormat::R16G16Sfloat,
            (Bits::Float, 2) => VkFormat::R32G32Sfloat,
            (Bits::Half, _) => VkFormat::R16G16B16A16Sfloat,
            (Bits::Float, _) => VkFormat::R32G32B32A32Sfloat,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            VkFormat::R16G16Sfloat => "VK_FORMAT_R16G16_SFLOAT",
            VkFormat::R16G16B16A16Sfloat => "VK_FORMAT_R16G16B16A16_SFLOAT",
            VkFormat::R32G32Sfloat => "VK_FORMAT_R32G32_SFLOAT",
            VkFormat::R32G32B32A32Sfloat => "VK_FORMAT_R32G32B32A32_SFLOAT",
        }
    }
}

/// DFD channel ids of the RGBSDA colour model: R = 0, G = 1, B = 2, A = 15.
const CHANNEL_IDS: [u8; 4] = [0, 1, 2, 15];
/// KHR_DF_SAMPLE_DATATYPE_FLOAT | KHR_DF_SAMPLE_DATATYPE_SIGNED, in the top nibble.
const FLOAT_SIGNED: u8 = 0x80 | 0x40;

/// The Basic Data Format Descriptor block for `channels` signed-float channels of `bits`
/// bits: RGBSDA colour model, BT.709 primaries, linear transfer, straight alpha, a 1×1×1×1
/// texel block, one plane, and per channel a sample with `sampleLower = −1.0f`,
/// `sampleUpper = 1.0f` (the specification's values for float formats).
pub fn basic_dfd_block(bits: Bits, channels: usize) -> Vec<u8> {
    let bits = bits.count();
    let texel_bytes = (bits / 8) as u8 * channels as u8;
    let block_size = 24 + 16 * channels;
    let mut b = Vec::with_capacity(block_size);
    // vendorId (17 bits) = 0 (Khronos), descriptorType (15 bits) = 0 (basic)
    b.extend_from_slice(&0u32.to_le_bytes());
    // versionNumber = 2 (KHR_DF_VERSIONNUMBER_1_3), descriptorBlockSize
    b.extend_from_slice(&2u16.to_le_bytes());
    b.extend_from_slice(&(block_size as u16).to_le_bytes());
    // colorModel RGBSDA = 1, colorPrimaries BT709 = 1, transferFunction LINEAR = 1,
    // flags ALPHA_STRAIGHT = 0
    b.extend_from_slice(&[1, 1, 1, 0]);
    // texelBlockDimension0..3, each stored as dimension − 1
    b.extend_from_slice(&[0, 0, 0, 0]);
    // bytesPlane0..7
    b.extend_from_slice(&[texel_bytes, 0, 0, 0, 0, 0, 0, 0]);
    for (c, &id) in CHANNEL_IDS.iter().enumerate().take(channels) {
        b.extend_from_slice(&((c as u32 * bits) as u16).to_le_bytes()); // bitOffset
        b.push((bits - 1) as u8); // bitLength − 1
        b.push(FLOAT_SIGNED | id); // channelType | qualifiers
        b.extend_from_slice(&[0, 0, 0, 0]); // samplePosition0..3
        b.extend_from_slice(&(-1.0f32).to_bits().to_le_bytes()); // sampleLower
        b.extend_from_slice(&1.0f32.to_bits().to_le_bytes()); // sampleUpper
    }
    debug_assert_eq!(b.len(), block_size);
    b
}

fn pad_to(bytes: &mut Vec<u8>, alignment: usize) {
    while !bytes.len().is_multiple_of(alignment) {
        bytes.push(0);
    }
}

fn lcm(a: usize, b: usize) -> usize {
    let (mut x, mut y) = (a, b);
    while y != 0 {
        (x, y) = (y, x % y);
    }
    a / x * b
}

/// Encodes `table` (2 or 4 channels) as a KTX 2.0 file in memory.
pub fn encode(table: &Table, bits: Bits) -> Vec<u8> {
    let channels = table.channels.len();
    let format = VkFormat::of(bits, channels);
    let type_size = bits.count() / 8;
    let texel_size = type_size as usize * channels;
    let texels = table.texel_bytes(bits);

    // Data Format Descriptor: dfdTotalSize, then the one block.
    let block = basic_dfd_block(bits, channels);
    let mut dfd = ((4 + block.len()) as u32).to_le_bytes().to_vec();
    dfd.extend_from_slice(&block);

    // Key/value data: entries sorted by key; each is keyAndValueByteLength, the key and its
    // NUL, the value (a NUL-terminated UTF-8 string for KTXwriter), padded to 4 bytes.
    let mut kvd = Vec::new();
    let mut entry = b"KTXwriter\0".to_vec();
    entry.extend_from_slice(concat!("gloffuse ", env!("CARGO_PKG_VERSION"), "\0").as_bytes());
    kvd.extend_from_slice(&(entry.len() as u32).to_le_bytes());
    kvd.extend_from_slice(&entry);
    pad_to(&mut kvd, 4);

    const HEADER: usize = 80;
    const LEVEL_INDEX: usize = 24;
    let dfd_offset = HEADER + LEVEL_INDEX;
    let kvd_offset = dfd_offset + dfd.len();
    let mut level_offset = kvd_offset + kvd.len();
    // mipPadding: level data starts at a multiple of lcm(texel block size, 4).
    let align = lcm(texel_size, 4);
    level_offset = level_offset.div_ceil(align) * align;

    let mut out = Vec::with_capacity(level_offset + texels.len());
    out.extend_from_slice(&IDENTIFIER);
    for v in [
        format as u32,
        type_size,
        table.width as u32,
        table.height as u32,
        0, // pixelDepth: not a 3D texture
        0, // layerCount: not an array
        1, // faceCount
        1, // levelCount: exactly one level, no mip chain to generate
        0, // supercompressionScheme: none
        dfd_offset as u32,
        dfd.len() as u32,
        kvd_offset as u32,
        kvd.len() as u32,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteOffset
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteLength
    for v in [level_offset, texels.len(), texels.len()] {
        out.extend_from_slice(&(v as u64).to_le_bytes());
    }
    out.extend_from_slice(&dfd);
    out.extend_from_slice(&kvd);
    out.resize(level_offset, 0);
    out.extend_from_slice(&texels);
    out
}
