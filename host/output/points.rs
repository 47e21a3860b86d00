//! Frames as binary PLY and as splashsurf's `.xyz` (three native-endian f32 per particle, no
//! header), for surface reconstruction straight from coil's output.

/// Binary little-endian PLY: position (float, m), velocity (m/s), density (kg/m^3), pressure
/// (Pa), viscosity (m^2/s), shear rate (1/s) and id per vertex.
pub fn encode_ply(position: &[[f64; 3]], velocity: &[[f32; 3]], scalars: [(&str, &[f32]); 4], id: &[u32], bytes: &mut Vec<u8>) {
    bytes.clear();
    let mut header = format!("ply\nformat binary_little_endian 1.0\nelement vertex {}\n", position.len());
    for name in ["x", "y", "z", "vx", "vy", "vz"] {
        header += &format!("property float {name}\n");
    }
    for (name, _) in &scalars {
        header += &format!("property float {name}\n");
    }
    header += "property uint id\nend_header\n";
    bytes.extend_from_slice(header.as_bytes());
    for i in 0..position.len() {
        position[i].iter().for_each(|&x| bytes.extend_from_slice(&(x as f32).to_le_bytes()));
        velocity[i].iter().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes()));
        scalars.iter().for_each(|(_, v)| bytes.extend_from_slice(&v[i].to_le_bytes()));
        bytes.extend_from_slice(&id[i].to_le_bytes());
    }
}

/// Positions as consecutive native-endian f32 triples (m).
pub fn encode_xyz(position: &[[f64; 3]], bytes: &mut Vec<u8>) {
    bytes.clear();
    position.iter().flatten().for_each(|&x| bytes.extend_from_slice(&(x as f32).to_ne_bytes()));
}
