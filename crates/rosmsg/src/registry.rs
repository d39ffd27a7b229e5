//! A set of parsed message specs keyed by `pkg/Type`, with dependency resolution and the
//! full ros2msg definition text that rosbag2 stores as MCAP schema data.

use crate::parse::{parse_message_from, ParseError};
use crate::spec::{BaseType, MessageSpec, TypeName};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum RegistryError {
    #[error(transparent)]
    Parse(#[from] ParseError),
    #[error("unknown message type {0:?} (known types: see Registry::type_names)")]
    UnknownType(String),
    #[error("{0:?} is not a message type name (expected pkg/Type or pkg/msg/Type)")]
    BadTypeName(String),
    #[error("type {0} is defined twice")]
    Duplicate(String),
    #[error("field {field} of {owner} has type {missing}, which is not in the registry")]
    MissingDependency {
        owner: String,
        field: String,
        missing: String,
    },
    #[error("type {0} contains itself (recursive types cannot be encoded)")]
    Recursive(String),
    #[error("reading {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
}

/// Line introducing each dependency block in a full definition (80 `=`).
pub const DEFINITION_SEPARATOR: &str =
    "================================================================================";

/// Parsed message specs keyed by `pkg/Type`.
#[derive(Debug, Clone, Default)]
pub struct Registry {
    specs: BTreeMap<TypeName, MessageSpec>,
}

impl Registry {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds an already parsed spec. A type may be added once.
    pub fn add(&mut self, spec: MessageSpec) -> Result<(), RegistryError> {
        if self.specs.contains_key(&spec.type_name) {
            return Err(RegistryError::Duplicate(spec.type_name.to_string()));
        }
        self.specs.insert(spec.type_name.clone(), spec);
        Ok(())
    }

    /// Parses `text` as the `.msg` of `package/name` and adds it.
    pub fn add_msg(&mut self, package: &str, name: &str, text: &str) -> Result<(), RegistryError> {
        self.add(parse_message_from(
            package,
            name,
            text,
            &format!("{package}/msg/{name}.msg"),
        )?)
    }

    /// Adds every `<root>/<pkg>/msg/<Type>.msg` below `root` (the layout of `msgs/interfaces`
    /// and of an installed ROS `share` directory). Returns how many types were added.
    pub fn add_tree(&mut self, root: &Path) -> Result<usize, RegistryError> {
        let io = |p: &Path, e| RegistryError::Io {
            path: p.display().to_string(),
            source: e,
        };
        let mut n = 0;
        let mut pkgs: Vec<_> = std::fs::read_dir(root)
            .map_err(|e| io(root, e))?
            .filter_map(|e| e.ok())
            .collect();
        pkgs.sort_by_key(|e| e.file_name());
        for pkg in pkgs {
            let msg_dir = pkg.path().join("msg");
            if !msg_dir.is_dir() {
                continue;
            }
            n += self.add_package_dir(&pkg.file_name().to_string_lossy(), &msg_dir)?;
        }
        Ok(n)
    }

    /// Adds every `<Type>.msg` in `msg_dir` as a type of `package`. Returns how many were added.
    pub fn add_package_dir(
        &mut self,
        package: &str,
        msg_dir: &Path,
    ) -> Result<usize, RegistryError> {
        let io = |p: &Path, e| RegistryError::Io {
            path: p.display().to_string(),
            source: e,
        };
        let mut files: Vec<_> = std::fs::read_dir(msg_dir)
            .map_err(|e| io(msg_dir, e))?
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "msg"))
            .collect();
        files.sort();
        for path in &files {
            let text = std::fs::read_to_string(path).map_err(|e| io(path, e))?;
            let name = path
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .to_string();
            self.add(parse_message_from(
                package,
                &name,
                &text,
                &path.display().to_string(),
            )?)?;
        }
        Ok(files.len())
    }

    /// The spec of `name` (`pkg/Type` or `pkg/msg/Type`), if known.
    pub fn get(&self, name: &str) -> Option<&MessageSpec> {
        self.specs.get(&TypeName::parse(name)?)
    }

    /// The spec of `name`, or an error saying the type is unknown.
    pub fn spec(&self, name: &str) -> Result<&MessageSpec, RegistryError> {
        let t =
            TypeName::parse(name).ok_or_else(|| RegistryError::BadTypeName(name.to_string()))?;
        self.specs
            .get(&t)
            .ok_or_else(|| RegistryError::UnknownType(name.to_string()))
    }

    pub fn spec_by_name(&self, t: &TypeName) -> Result<&MessageSpec, RegistryError> {
        self.specs
            .get(t)
            .ok_or_else(|| RegistryError::UnknownType(t.to_string()))
    }

    /// All known types, sorted.
    pub fn type_names(&self) -> impl Iterator<Item = &TypeName> {
        self.specs.keys()
    }

    /// All known types as ROS 2 names `pkg/msg/Type`, sorted.
    pub fn ros_type_names(&self) -> Vec<String> {
        self.specs.keys().map(|t| t.ros_type()).collect()
    }

    pub fn specs(&self) -> impl Iterator<Item = &MessageSpec> {
        self.specs.values()
    }

    pub fn len(&self) -> usize {
        self.specs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.specs.is_empty()
    }

    /// Checks that every nested type is known and that no type contains itself.
    pub fn check(&self) -> Result<(), RegistryError> {
        for spec in self.specs.values() {
            for f in &spec.fields {
                if let BaseType::Message(t) = &f.ty.base {
                    if !self.specs.contains_key(t) {
                        return Err(RegistryError::MissingDependency {
                            owner: spec.type_name.to_string(),
                            field: f.name.clone(),
                            missing: t.to_string(),
                        });
                    }
                }
            }
        }
        for t in self.specs.keys() {
            self.check_acyclic(t, &mut Vec::new())?;
        }
        Ok(())
    }

    fn check_acyclic(&self, t: &TypeName, stack: &mut Vec<TypeName>) -> Result<(), RegistryError> {
        if stack.contains(t) {
            return Err(RegistryError::Recursive(t.to_string()));
        }
        stack.push(t.clone());
        if let Some(spec) = self.specs.get(t) {
            for dep in spec.nested_types() {
                self.check_acyclic(&dep, stack)?;
            }
        }
        stack.pop();
        Ok(())
    }

    /// Every type `name` depends on, transitively, each once, in the order the full definition
    /// lists them.
    pub fn dependencies(&self, name: &str) -> Result<Vec<TypeName>, RegistryError> {
        let root = self.spec(name)?;
        let mut seen = BTreeSet::new();
        let mut out = Vec::new();
        self.walk_dependencies(root, &mut seen, &mut out, 0)?;
        Ok(out)
    }

    /// Depth-first walk in rosbag2's order: a type's direct dependencies sorted by name (rosbag2
    /// keeps them in a `std::set<std::string>`), each followed at once by its own dependencies.
    fn walk_dependencies(
        &self,
        spec: &MessageSpec,
        seen: &mut BTreeSet<TypeName>,
        out: &mut Vec<TypeName>,
        depth: usize,
    ) -> Result<(), RegistryError> {
        if depth > 64 {
            return Err(RegistryError::Recursive(spec.type_name.to_string()));
        }
        let mut direct: Vec<TypeName> = spec.nested_types();
        direct.sort_by_key(|t| t.short());
        for dep in direct {
            if seen.insert(dep.clone()) {
                let dep_spec =
                    self.specs
                        .get(&dep)
                        .ok_or_else(|| RegistryError::MissingDependency {
                            owner: spec.type_name.to_string(),
                            field: spec
                                .fields
                                .iter()
                                .find(|f| f.ty.base == BaseType::Message(dep.clone()))
                                .map(|f| f.name.clone())
                                .unwrap_or_default(),
                            missing: dep.to_string(),
                        })?;
                out.push(dep);
                self.walk_dependencies(dep_spec, seen, out, depth + 1)?;
            }
        }
        Ok(())
    }

    /// The full ros2msg definition of `name`, as rosbag2 writes it into MCAP schema data
    /// (`rosbag2_cpp` `LocalMessageDefinitionSource::get_full_text`): the type's own `.msg`
    /// text verbatim, then for each dependency (see [`Registry::dependencies`] for the order)
    /// a newline, a line of 80 `=`, a line `MSG: pkg/Type`, and that type's `.msg` text.
    pub fn full_definition(&self, name: &str) -> Result<String, RegistryError> {
        let root = self.spec(name)?;
        let mut out = root.text.clone();
        for dep in self.dependencies(name)? {
            let spec = self.spec_by_name(&dep)?;
            out.push('\n');
            out.push_str(DEFINITION_SEPARATOR);
            out.push_str("\nMSG: ");
            out.push_str(&dep.short());
            out.push('\n');
            out.push_str(&spec.text);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reg() -> Registry {
        let mut r = Registry::new();
        r.add_msg("builtin_interfaces", "Time", "int32 sec\nuint32 nanosec\n")
            .unwrap();
        r.add_msg(
            "std_msgs",
            "Header",
            "builtin_interfaces/Time stamp\nstring frame_id\n",
        )
        .unwrap();
        r.add_msg(
            "geometry_msgs",
            "Point",
            "float64 x\nfloat64 y\nfloat64 z\n",
        )
        .unwrap();
        r.add_msg("pkg", "Inner", "geometry_msgs/Point p\n")
            .unwrap();
        r.add_msg(
            "pkg",
            "Outer",
            "std_msgs/Header header\nInner[] inner\ngeometry_msgs/Point q\n",
        )
        .unwrap();
        r
    }

    #[test]
    fn full_definition_follows_rosbag2_order() {
        let r = reg();
        r.check().unwrap();
        // Direct deps sorted: geometry_msgs/Point, pkg/Inner, std_msgs/Header; Inner's Point already seen.
        let deps: Vec<String> = r
            .dependencies("pkg/msg/Outer")
            .unwrap()
            .iter()
            .map(|t| t.short())
            .collect();
        assert_eq!(
            deps,
            [
                "geometry_msgs/Point",
                "pkg/Inner",
                "std_msgs/Header",
                "builtin_interfaces/Time"
            ]
        );
        let sep = "=".repeat(80);
        let expected = format!(
            "std_msgs/Header header\nInner[] inner\ngeometry_msgs/Point q\n\n{sep}\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n\n{sep}\nMSG: pkg/Inner\ngeometry_msgs/Point p\n\n{sep}\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\n{sep}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
        );
        assert_eq!(r.full_definition("pkg/Outer").unwrap(), expected);
        assert_eq!(
            r.full_definition("geometry_msgs/Point").unwrap(),
            "float64 x\nfloat64 y\nfloat64 z\n"
        );
    }

    #[test]
    fn missing_and_unknown_types_are_errors() {
        let mut r = reg();
        r.add_msg("pkg", "Broken", "pkg/Nope n\n").unwrap();
        let e = r.check().unwrap_err().to_string();
        assert!(
            e.contains("pkg/Broken") && e.contains("pkg/Nope") && e.contains("field n"),
            "{e}"
        );
        assert!(matches!(
            r.spec("pkg/Missing"),
            Err(RegistryError::UnknownType(_))
        ));
        assert!(matches!(
            r.spec("not a type"),
            Err(RegistryError::BadTypeName(_))
        ));
        assert!(matches!(
            r.add_msg("pkg", "Inner", "int8 a\n"),
            Err(RegistryError::Duplicate(_))
        ));
        let mut r2 = Registry::new();
        r2.add_msg("pkg", "A", "pkg/B b\n").unwrap();
        r2.add_msg("pkg", "B", "pkg/A a\n").unwrap();
        assert!(matches!(r2.check(), Err(RegistryError::Recursive(_))));
    }
}
