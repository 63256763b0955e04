//! `[object]` as a rig of AprilTags (`[[object.tags]]`, `[object.rig]`): each tag checked with
//! an error naming its key, and the object's points, the tags' corners (four per tag, in
//! OpenCV aruco's order).

use super::{check_positive, check_values, pose_of};
use crate::sim::error::Result;
use crate::sim::scenario::scenario_error;
use crate::sim::scenario::schema::ObjectSpec;
use crate::vision::TagFamily;
use crate::vision::tags::TagFace;
use crate::vision::target::tags::{RigTag, TagRig};

impl ObjectSpec {
    /// The tag rig, if `tags` are given (then neither `points` nor `normals` may be).
    pub(super) fn tag_rig(&self) -> Result<Option<TagRig>> {
        if self.tags.is_empty() {
            if self.tag_family.is_some() {
                return Err(scenario_error("object.tag_family", "is the tags' family: give [[object.tags]] too"));
            }
            if self.rig.is_some() {
                return Err(scenario_error("object.rig", "places tags: give [[object.tags]] too"));
            }
            return Ok(None);
        }
        if !self.points.is_empty() {
            return Err(scenario_error("object.points", "give points (dots) or tags, not both"));
        }
        if self.normals.is_some() {
            return Err(scenario_error("object.normals", "are the dots' normals: a tag's is its rotation"));
        }
        let rig = match &self.rig {
            Some(r) => {
                check_values("object.rig.position", &r.position)?;
                check_values("object.rig.rotation_deg", &r.rotation_deg)?;
                pose_of(r.position, r.rotation_deg)
            }
            None => nalgebra::Isometry3::identity(),
        };
        let family = self.family()?;
        let count = TagFace::count(family).map_err(|e| scenario_error("object.tag_family", e.to_string()))?;
        let mut tags = Vec::with_capacity(self.tags.len());
        for (i, t) in self.tags.iter().enumerate() {
            let key = |k: &str| format!("object.tags[{i}].{k}");
            if t.id >= count {
                return Err(scenario_error(
                    &key("id"),
                    format!("a {} id, 0 to {}, got {}", family.name(), count - 1, t.id),
                ));
            }
            if let Some(j) = self.tags[..i].iter().position(|o| o.id == t.id) {
                return Err(scenario_error(&key("id"), format!("id {} is also object.tags[{j}]'s", t.id)));
            }
            check_positive(&key("size"), t.size)?;
            check_values(&key("size"), &[t.size])?;
            check_values(&key("position"), &t.position)?;
            check_values(&key("rotation_deg"), &t.rotation_deg)?;
            tags.push(RigTag { id: t.id, size: t.size, pose: rig * pose_of(t.position, t.rotation_deg) });
        }
        TagRig::new(family, tags).map(Some).map_err(|e| scenario_error("object.tags", e.to_string()))
    }

    /// `object.tag_family`, tag36h11 when absent; another name is an error naming the key and
    /// listing the names ([`TagFamily::NAMES`]).
    fn family(&self) -> Result<TagFamily> {
        let Some(name) = &self.tag_family else { return Ok(TagFamily::default()) };
        TagFamily::from_name(name).ok_or_else(|| {
            let names = TagFamily::NAMES.map(|n| format!("{n:?}")).join(", ");
            scenario_error("object.tag_family", format!("expected one of {names}, got {name:?}"))
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use crate::sim::scenario::{Scenario, builtin};
    use crate::vision::Target;

    fn error_of(edit: impl Fn(&mut Scenario)) -> String {
        let mut s = builtin("tags-12-6").unwrap();
        edit(&mut s);
        s.to_config().unwrap_err().to_string()
    }

    #[test]
    fn the_points_of_a_rig_are_its_tags_corners() {
        let config = builtin("tags-12-12").unwrap().to_config().unwrap();
        let tags = config.scene.tags().expect("a tag rig");
        let ids: Vec<u32> = tags.points().iter().map(|p| p.id).collect();
        assert_eq!(ids, (4..16).collect::<Vec<u32>>());
        assert_eq!(config.scene.points().len(), 12);

        for p in config.scene.points() {
            let d = nalgebra::Vector3::new(p[0], p[1], p[2] - 0.75);
            assert!((d.norm() - (0.075f64.powi(2) + 2.0 * 0.05f64.powi(2)).sqrt()).abs() < 1e-4, "{p:?}");
        }
    }

    #[test]
    fn tag_key_errors_name_the_key() {
        type Change = Box<dyn Fn(&mut Scenario)>;
        let cases: Vec<(Change, &str)> = vec![
            (Box::new(|s| s.object.tags[1].id = 587), "object.tags[1].id"),
            (Box::new(|s| s.object.tags[2].id = 1), "object.tags[2].id"),
            (Box::new(|s| s.object.tags[0].size = -0.01), "object.tags[0].size"),
            (Box::new(|s| s.object.tags[0].position[1] = f64::NAN), "object.tags[0].position[1]"),
            (Box::new(|s| s.object.tags[2].rotation_deg[0] = f64::INFINITY), "object.tags[2].rotation_deg[0]"),
            (Box::new(|s| s.object.points = vec![[0.0, 0.0, 1.0]]), "object.points"),
            (Box::new(|s| s.object.normals = Some(vec![[0.0, 0.0, -1.0]; 12])), "object.normals"),
            (Box::new(|s| s.object.tags.truncate(1)), "object.tags"),
            (Box::new(|s| s.object.rig.as_mut().unwrap().position[2] = -0.65), "object.tags[0]"),
            (
                Box::new(|s| {
                    s.object.tags.clear();
                    s.object.points = vec![[0.0, 0.0, 1.0]; 6];
                }),
                "object.rig",
            ),
        ];
        for (edit, key) in cases {
            let err = error_of(edit);
            assert!(err.contains(key), "{key}: {err}");
        }
    }

    #[test]
    fn the_family_key_is_read_and_checked_against_the_families() {
        let mut s = builtin("tags-12-6").unwrap();
        s.object.tag_family = Some("tagStandard41h12".into());
        s.object.tags[0].id = 2114;
        let config = s.to_config().unwrap();
        let rig = config.scene.tags().expect("a tag rig");
        assert_eq!(rig.family(), crate::vision::TagFamily::TagStandard41h12);
        assert_eq!(
            builtin("tags-12-6").unwrap().to_config().unwrap().scene.tags().unwrap().family().name(),
            "tag36h11"
        );
        let err = error_of(|s| s.object.tag_family = Some("tag36h12".into()));
        assert!(err.contains("object.tag_family"), "{err}");
        for name in crate::vision::TagFamily::NAMES {
            assert!(err.contains(&format!("{name:?}")), "{name}: {err}");
        }
        let err = error_of(|s| {
            s.object.tag_family = Some("tagCircle21h7".into());
            s.object.tags[2].id = 38;
        });
        assert!(err.contains("object.tags[2].id") && err.contains("tagCircle21h7 id, 0 to 37"), "{err}");
        let err = error_of(|s| {
            s.object.tags.clear();
            s.object.rig = None;
            s.object.points = vec![[0.0, 0.0, 1.0]; 6];
            s.object.tag_family = Some("tag25h9".into());
        });
        assert!(err.contains("object.tag_family"), "{err}");
    }
}
