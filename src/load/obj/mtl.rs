//! Wavefront MTL material libraries, read into the statements raylab maps onto
//! its glTF-style material (see README.md, "OBJ/MTL"): `Kd`, `Ks`, `Ns`, `Ke`,
//! `Ni`, `d`/`Tr`, `Tf`, `illum`, the maps `map_Kd`, `map_Ks`, `map_d`,
//! `map_Bump`/`bump`, `norm`, and the PBR extension `Pr`, `Pm`, `map_Pr`,
//! `map_Pm`, `map_Ke`. Other statements are skipped with one warning per kind.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3A};

use super::error::ObjError;

/// A texture statement: the file and the options raylab reads.
#[derive(Clone, Debug, PartialEq)]
pub struct MapRef {
    /// The image file (relative paths resolved against the MTL's folder).
    pub path: PathBuf,
    /// `-o u v`: offset of the texture coordinates.
    pub offset: Vec2,
    /// `-s u v`: scale of the texture coordinates.
    pub scale: Vec2,
    /// `-clamp on`: clamp instead of repeat.
    pub clamp: bool,
    /// `-bm`: bump multiplier.
    pub bump_multiplier: f32,
}

/// One `newmtl` with the statements raylab reads (absent ones `None`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    /// The name `usemtl` refers to.
    pub name: String,
    /// Diffuse colour.
    pub kd: Option<Vec3A>,
    /// Specular colour.
    pub ks: Option<Vec3A>,
    /// Phong exponent.
    pub ns: Option<f32>,
    /// Emitted radiance.
    pub ke: Option<Vec3A>,
    /// Index of refraction.
    pub ni: Option<f32>,
    /// Opacity (`d`, or `1 − Tr`).
    pub dissolve: Option<f32>,
    /// Transmission filter (a glass's tint).
    pub tf: Option<Vec3A>,
    /// Illumination model.
    pub illum: Option<u32>,
    /// PBR extension: roughness.
    pub pr: Option<f32>,
    /// PBR extension: metallic.
    pub pm: Option<f32>,
    /// `map_Kd`.
    pub map_kd: Option<MapRef>,
    /// `map_Ks`.
    pub map_ks: Option<MapRef>,
    /// `map_d`.
    pub map_d: Option<MapRef>,
    /// `map_Bump` / `bump`.
    pub bump: Option<MapRef>,
    /// `norm`.
    pub norm: Option<MapRef>,
    /// `map_Pr`.
    pub map_pr: Option<MapRef>,
    /// `map_Pm`.
    pub map_pm: Option<MapRef>,
    /// `map_Ke`.
    pub map_ke: Option<MapRef>,
}

/// Statements MTL files commonly hold that have no meaning for raylab's
/// material (ambient colour and its map, sharpness, anti-aliasing): skipped
/// without a warning.
const SILENT: &[&str] = &["Ka", "map_Ka", "sharpness", "map_aat", "Km"];

/// Parses MTL text; `path` names the file in errors and locates textures.
/// Unknown statements are counted into `skipped` by kind.
pub fn parse_mtl(
    text: &str,
    path: &Path,
    skipped: &mut BTreeMap<String, usize>,
) -> Result<Vec<MtlMaterial>, ObjError> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out: Vec<MtlMaterial> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let syntax = |message: String| ObjError::Syntax {
            path: path.to_owned(),
            line: line_no,
            message,
        };
        let line = raw.split('#').next().unwrap_or("").trim();
        let Some(keyword) = line.split_ascii_whitespace().next() else {
            continue;
        };
        let rest = line[keyword.len()..].trim();
        let numbers = |n: usize| -> Result<Vec<f32>, ObjError> {
            let v: Vec<f32> = rest
                .split_ascii_whitespace()
                .map(|w| w.parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|_| {
                    syntax(format!(
                        "{keyword} needs {n} number(s), got '{}'",
                        crate::guard::quote(rest)
                    ))
                })?;
            if v.len() < n || v.iter().any(|x| !x.is_finite()) {
                return Err(syntax(format!(
                    "{keyword} needs {n} finite number(s), got '{}'",
                    crate::guard::quote(rest)
                )));
            }
            Ok(v)
        };
        // A single number may stand for a grey colour (`Ks 0.5`).
        let color = || -> Result<Vec3A, ObjError> {
            let v = numbers(1)?;
            Ok(if v.len() >= 3 {
                Vec3A::new(v[0], v[1], v[2])
            } else {
                Vec3A::splat(v[0])
            }
            .max(Vec3A::ZERO))
        };
        if keyword == "newmtl" {
            if rest.is_empty() {
                return Err(syntax("newmtl needs a name".into()));
            }
            out.push(MtlMaterial {
                name: rest.to_string(),
                ..MtlMaterial::default()
            });
            continue;
        }
        let Some(m) = out.last_mut() else {
            if !SILENT.contains(&keyword) {
                *skipped
                    .entry(format!("{keyword} (before any newmtl)"))
                    .or_default() += 1;
            }
            continue;
        };
        match keyword {
            "Kd" => m.kd = Some(color()?),
            "Ks" => m.ks = Some(color()?),
            "Ke" => m.ke = Some(color()?),
            "Tf" => m.tf = Some(color()?.min(Vec3A::ONE)),
            "Ns" => m.ns = Some(numbers(1)?[0].max(0.0)),
            "Ni" => m.ni = Some(numbers(1)?[0]),
            "d" => m.dissolve = Some(numbers(1)?[0].clamp(0.0, 1.0)),
            "Tr" => m.dissolve = Some(1.0 - numbers(1)?[0].clamp(0.0, 1.0)),
            "Pr" => m.pr = Some(numbers(1)?[0].clamp(0.0, 1.0)),
            "Pm" => m.pm = Some(numbers(1)?[0].clamp(0.0, 1.0)),
            "illum" => {
                m.illum = Some(rest.parse::<u32>().map_err(|_| {
                    syntax(format!(
                        "illum needs a model number, got '{}'",
                        crate::guard::quote(rest)
                    ))
                })?)
            }
            "map_Kd" | "map_Ks" | "map_d" | "map_Bump" | "map_bump" | "bump" | "norm"
            | "map_Pr" | "map_Pm" | "map_Ke" => {
                let map = map_statement(rest, dir, skipped).map_err(syntax)?;
                let slot = match keyword {
                    "map_Kd" => &mut m.map_kd,
                    "map_Ks" => &mut m.map_ks,
                    "map_d" => &mut m.map_d,
                    "norm" => &mut m.norm,
                    "map_Pr" => &mut m.map_pr,
                    "map_Pm" => &mut m.map_pm,
                    "map_Ke" => &mut m.map_ke,
                    _ => &mut m.bump,
                };
                *slot = Some(map);
            }
            k if SILENT.contains(&k) => {}
            k => *skipped.entry(k.to_string()).or_default() += 1,
        }
    }
    Ok(out)
}

/// A texture statement's options and file name (the rest of the line after
/// the options, so names may hold spaces).
fn map_statement(
    rest: &str,
    dir: &Path,
    skipped: &mut BTreeMap<String, usize>,
) -> Result<MapRef, String> {
    let mut map = MapRef {
        path: PathBuf::new(),
        offset: Vec2::ZERO,
        scale: Vec2::ONE,
        clamp: false,
        bump_multiplier: 1.0,
    };
    // Tokens with their positions, so that the file name can be the rest of
    // the line after the options.
    let mut tokens: Vec<(usize, &str)> = Vec::new();
    let mut start = None;
    for (i, c) in rest.char_indices().chain([(rest.len(), ' ')]) {
        match (c.is_whitespace(), start) {
            (false, None) => start = Some(i),
            (true, Some(s)) => {
                tokens.push((s, &rest[s..i]));
                start = None;
            }
            _ => {}
        }
    }
    let mut k = 0;
    while k + 1 < tokens.len() {
        let Some(option) = tokens[k].1.strip_prefix('-') else {
            break;
        };
        let (most, numeric) = match option {
            "o" | "s" | "t" => (3, true),
            "mm" => (2, true),
            "bm" | "boost" | "texres" => (1, true),
            "clamp" | "blendu" | "blendv" | "imfchan" | "type" | "cc" => (1, false),
            // Not an option raylab knows: the file name starts here.
            _ => break,
        };
        k += 1;
        let mut args: Vec<&str> = Vec::new();
        // Always leave one token for the file name.
        while args.len() < most && k + 1 < tokens.len() {
            let a = tokens[k].1;
            if numeric && a.parse::<f32>().is_err() {
                break;
            }
            args.push(a);
            k += 1;
        }
        let nums: Vec<f32> = args.iter().filter_map(|a| a.parse::<f32>().ok()).collect();
        if args.is_empty() || nums.iter().any(|x| !x.is_finite()) {
            return Err(format!("texture option -{option} needs a value"));
        }
        match option {
            "o" => map.offset = Vec2::new(nums[0], nums.get(1).copied().unwrap_or(0.0)),
            "s" => map.scale = Vec2::new(nums[0], nums.get(1).copied().unwrap_or(1.0)),
            "bm" => map.bump_multiplier = nums[0],
            "clamp" => map.clamp = args[0] == "on",
            _ => {
                *skipped
                    .entry(format!("texture option -{option}"))
                    .or_default() += 1
            }
        }
    }
    let words = tokens.get(k).map_or("", |&(s, _)| &rest[s..]);
    let name = words.trim();
    if name.is_empty() {
        return Err("texture statement without a file name".into());
    }
    // Exporters on Windows write backslashes.
    let name = name.replace('\\', "/");
    map.path = dir.join(name);
    Ok(map)
}

/// Roughness from a Phong exponent: the Beckmann width that matches it,
/// `α = sqrt(2 / (Ns + 2))` (Walter et al. 2007), and glTF's `roughness = sqrt(α)`
/// (since glTF's `α = roughness²`).
pub fn phong_roughness(ns: f32) -> f32 {
    let ns = if ns.is_finite() { ns.max(0.0) } else { 0.0 };
    (2.0 / (ns + 2.0)).sqrt().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> (Vec<MtlMaterial>, BTreeMap<String, usize>) {
        let mut skipped = BTreeMap::new();
        let m = parse_mtl(text, Path::new("dir/m.mtl"), &mut skipped).unwrap();
        (m, skipped)
    }

    #[test]
    fn statements_are_read() {
        let (m, skipped) = parse(
            "newmtl a b\nKd 0.5 0.25 1\nKs 0.5\nNs 96\nKe 1 2 3\nNi 1.45\nd 0.5\nillum 2\n\
             Pr 0.3\nPm 1\nTf 0.9 0.8 0.7\nKa 1 1 1\n\
             map_Kd -s 2 2 -o 0.5 0.25 tex/my wood.png\nmap_Bump -bm 0.4 h.png\nnorm n.png\n\
             map_d -clamp on m.png\nmap_Pr r.png\nmap_Pm m.png\nmap_Ke e.png\nmap_Ks s.png\n\
             Ps 1\nPs 2\naniso 0.1\nnewmtl second\nTr 0.25\n",
        );
        assert_eq!(m.len(), 2);
        let a = &m[0];
        assert_eq!(a.name, "a b");
        assert_eq!(a.kd, Some(Vec3A::new(0.5, 0.25, 1.0)));
        assert_eq!(a.ks, Some(Vec3A::splat(0.5)));
        assert_eq!(
            (a.ns, a.ni, a.dissolve, a.illum),
            (Some(96.0), Some(1.45), Some(0.5), Some(2))
        );
        assert_eq!((a.pr, a.pm), (Some(0.3), Some(1.0)));
        assert_eq!(a.tf, Some(Vec3A::new(0.9, 0.8, 0.7)));
        let kd = a.map_kd.as_ref().unwrap();
        assert_eq!(kd.path, Path::new("dir/tex/my wood.png"));
        assert_eq!(
            (kd.scale, kd.offset),
            (Vec2::splat(2.0), Vec2::new(0.5, 0.25))
        );
        assert_eq!(a.bump.as_ref().unwrap().bump_multiplier, 0.4);
        assert!(a.map_d.as_ref().unwrap().clamp);
        for map in [&a.norm, &a.map_pr, &a.map_pm, &a.map_ke, &a.map_ks] {
            assert!(map.is_some());
        }
        assert_eq!(m[1].dissolve, Some(0.75));
        // One count per unknown kind; Ka is silent.
        assert_eq!(skipped.get("Ps"), Some(&2));
        assert_eq!(skipped.get("aniso"), Some(&1));
        assert_eq!(skipped.len(), 2, "{skipped:?}");
    }

    #[test]
    fn errors_name_the_line() {
        let mut skipped = BTreeMap::new();
        let mut err = |text: &str| {
            parse_mtl(text, Path::new("m.mtl"), &mut skipped)
                .unwrap_err()
                .to_string()
        };
        assert_eq!(
            err("newmtl a\nKd 1 x 1\n"),
            "m.mtl:2: Kd needs 1 number(s), got '1 x 1'"
        );
        assert_eq!(
            err("newmtl a\nNs nan\n"),
            "m.mtl:2: Ns needs 1 finite number(s), got 'nan'"
        );
        assert_eq!(
            err("newmtl a\nmap_Kd -s 2\n"),
            "m.mtl:2: texture option -s needs a value"
        );
        assert_eq!(
            err("newmtl a\nmap_Kd\n"),
            "m.mtl:2: texture statement without a file name"
        );
        assert_eq!(err("newmtl\n"), "m.mtl:1: newmtl needs a name");
        assert_eq!(
            err("newmtl a\nillum two\n"),
            "m.mtl:2: illum needs a model number, got 'two'"
        );
    }

    #[test]
    fn phong_exponents_map_to_roughness() {
        // Ns = 0: α = 1, the roughest; Ns = 2: α = sqrt(1/2); large Ns: smooth.
        assert_eq!(phong_roughness(0.0), 1.0);
        assert!((phong_roughness(2.0) - 0.5f32.sqrt().sqrt()).abs() < 1e-6);
        assert!(phong_roughness(10_000.0) < 0.12);
        assert!(phong_roughness(96.0) > phong_roughness(500.0));
    }
}
