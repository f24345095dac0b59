//! The decisions on a split node's parts (pure): how the views see a node (`NodeEval`), its
//! children seen as quadrants and sixteenths (`Quadrant`), the triangles each mesh costs, and
//! the fewest triangles that meet τ (`choose_parts`).

/// A node as the views see it.
#[derive(Clone, Copy)]
pub(super) struct NodeEval {
    pub(super) eps: f64,
    /// Largest ρ (px) among the views that see the node.
    pub(super) rho_px: f64,
    /// Largest ρ/τ among them: the node meets every channel's bound when ≤ 1.
    pub(super) rho_norm: f64,
    /// The largest f·g/τ among them (focal length times the box's vertical gain — on the
    /// ellipsoid along the node's centre normal —, over τ): with [`Self::gain_slack`], what
    /// bounds a part of the node from its box alone (`Frame::quadrants_within`).
    pub(super) gain: f64,
    /// [`Self::gain_slack`] (never negative) with its sign bit set when the node
    /// [`Self::straddles`]. One word for both keeps the record at five words, so the three an
    /// evaluation returns (120 bytes) are copied inline, not through `memcpy` — a sixth word
    /// made the selection on the ellipsoid ~1.3× slower.
    slack_straddles: f64,
}

impl NodeEval {
    pub(super) fn new(
        eps: f64,
        rho_px: f64,
        rho_norm: f64,
        gain: f64,
        gain_slack: f64,
        straddles: bool,
    ) -> Self {
        debug_assert!(gain_slack >= 0.0 || gain_slack.is_nan());
        let magnitude = gain_slack.abs();
        Self {
            eps,
            rho_px,
            rho_norm,
            gain,
            slack_straddles: if straddles { -magnitude } else { magnitude },
        }
    }

    /// On the ellipsoid the largest f·c/τ among the views that see the node (c the box's
    /// obliquity, what a unit of gain slack adds); 0 on the plane.
    #[inline]
    pub(super) fn gain_slack(&self) -> f64 {
        self.slack_straddles.abs()
    }

    /// Some view that sees the node has a corner of its box outside one of its frustum's
    /// planes: a part of the node may be unseen (`Frame::seen_parts`).
    #[inline]
    pub(super) fn straddles(&self) -> bool {
        self.slack_straddles.is_sign_negative()
    }
}

/// A child of a split node seen as a quadrant of it (`Frame::quadrants`).
#[derive(Clone, Copy)]
pub(super) enum Quadrant {
    /// All padding: never drawn.
    NoTerrain,
    /// No view sees it.
    Unseen,
    /// `q` at the parent's resolution, `own` at its own, `sub` at the grandparent's (a
    /// sixteenth of it) when that is measured and asked for.
    Seen {
        q: NodeEval,
        own: NodeEval,
        sub: Option<NodeEval>,
    },
}

/// What [`Frame::upgrade_quadrants`](super::walk::Frame::upgrade_quadrants) found of a child
/// that missed τ as a quadrant but meets it itself, its children bounded from its box.
// Four of these live on the stack while one node's children are walked; boxing the large
// variant would allocate per child instead.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy)]
pub(super) enum Upgrade {
    /// Not tried (or drawn as a quadrant after all): nothing to remember.
    Untried,
    /// Best drawn whole: walked, it need not be tried in parts again.
    Whole,
    /// Best drawn child by child, with these children: walked, it takes them instead of
    /// bounding them again (the same call on the same values).
    Children([Quadrant; 4]),
}

/// What one more instance costs beside its triangles (its ~450-byte record, its vertex
/// setup), weighed in triangles: at 64 the lavapipe suite's Inn valley and Northern England
/// flights drew the same triangles at equal error (within 2 %) as at 0, with 17 % fewer
/// instances (16385² flat, 720p: 1,883 instead of 2,266).
pub(super) const INSTANCE_TRIANGLES: u32 = 64;

/// How near τ (ρ/τ) a child's sixteenth bounded from its parent's box must come for
/// `Frame::quadrants_meeting` to evaluate it exactly as well. Lavapipe suite's Inn valley,
/// Sierra Nevada and Northern England flights, bounded's triangles over τ = 0.5..10 against
/// the box bound alone: −0.7 % to −1.1 % at 1.5, −1.1 % to −1.5 % at any reach (an exact
/// evaluation of every child); selection CPU (16385², 720p, τ = 1) on the ellipsoid 79 → 95 µs
/// at 1.5 (143 µs at any reach), on the plane 275 → 356 µs (415 µs).
pub(super) const HYBRID_REACH: f64 = 1.5;

/// Triangles of the three meshes a node may be drawn with (`mesh`): whole, as a quadrant
/// (stride 2), as a sixteenth (stride 4) — the grid and two edges' skirts — and what an
/// instance costs besides ([`INSTANCE_TRIANGLES`]). Two edges, not four: most edges are bare
/// or filled (`select::node_skirts`), and on the lavapipe suite's Inn and Sierra Nevada
/// flights skirts and fills are 5.5 % of bounded's triangles, about half of every node's
/// four skirts. Weighing two edges drew 0.995× the triangles of weighing four (geometric mean
/// over the suite's 320 bounded configurations, 0.91–1.00×; every max error the same).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct MeshCosts {
    pub(super) whole: u32,
    pub(super) quadrant: u32,
    pub(super) sixteenth: u32,
    pub(super) instance: u32,
}

impl MeshCosts {
    /// For tiles of `q` quads a side (a tile of k quads: 2k² triangles and two edges' skirts,
    /// `mesh::skirt_edge_triangles`).
    pub(super) fn of(q: u32) -> Self {
        let tris = |k: u32| 2 * k * k + 2 * crate::mesh::skirt_edge_triangles(k);
        Self {
            whole: tris(q),
            quadrant: tris(q / 2),
            sixteenth: tris(q / 4),
            instance: INSTANCE_TRIANGLES,
        }
    }
}

/// How a node whose children were evaluated (`Frame::quadrants`, with their sixteenths)
/// is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Parts {
    /// The node whole at its own resolution, with this ρ (px) — `None`: its own evaluation's.
    Whole(Option<f64>),
    /// The node as a quadrant of its parent, at the parent's resolution: each seen child meets
    /// τ as a sixteenth there, so the node's surface does wherever it is seen. The largest ρ
    /// (px) and ρ/τ of the sixteenths.
    AsQuadrant { rho_px: f64, rho_norm: f64 },
    /// Child by child: a sixteenth where it meets τ so, else a quadrant where it meets τ so,
    /// else the child at its own resolution or split further (never drawn when unseen).
    Children,
}

/// The fewest triangles (instances weighed in) that meet τ for a node with children `quads`:
/// the node whole (when it meets τ itself, or every seen child does at the node's resolution,
/// so the node does wherever it is seen), as a quadrant of its parent, or child by child — chosen only when
/// every seen child then meets τ as a sixteenth or quadrant. Ties go to fewer instances. When
/// some seen child needs more than the node's resolution: whole if the node meets τ, else
/// [`Parts::Children`], the children walked.
pub(super) fn choose_parts(quads: &[Quadrant; 4], own_meets_tau: bool, cost: MeshCosts) -> Parts {
    let mut children = 0u32;
    // Every seen child meets τ: as a sixteenth (`all_sub`); at the node's resolution
    // (`all_q`, so the node drawn whole does); in one of the two (`within`).
    let (mut all_sub, mut all_q, mut within) = (true, true, true);
    let (mut sub_rho, mut sub_norm, mut q_rho) = (0f64, 0f64, 0f64);
    for quad in quads {
        match quad {
            Quadrant::NoTerrain | Quadrant::Unseen => {}
            Quadrant::Seen { q, sub, .. } => match sub {
                Some(s) if s.rho_norm <= 1.0 => {
                    children += cost.sixteenth + cost.instance;
                    (sub_rho, sub_norm) = (sub_rho.max(s.rho_px), sub_norm.max(s.rho_norm));
                    all_q &= q.rho_norm <= 1.0;
                    q_rho = q_rho.max(q.rho_px);
                }
                _ if q.rho_norm <= 1.0 => {
                    children += cost.quadrant + cost.instance;
                    all_sub = false;
                    q_rho = q_rho.max(q.rho_px);
                }
                _ => (all_sub, all_q, within) = (false, false, false),
            },
        }
    }
    if !within {
        return if own_meets_tau {
            Parts::Whole(None)
        } else {
            Parts::Children
        };
    }
    if all_sub && cost.quadrant + cost.instance <= children && cost.quadrant <= cost.whole {
        return Parts::AsQuadrant {
            rho_px: sub_rho,
            rho_norm: sub_norm,
        };
    }
    if (own_meets_tau || all_q) && cost.whole + cost.instance <= children {
        return Parts::Whole((!own_meets_tau).then_some(q_rho));
    }
    Parts::Children
}
